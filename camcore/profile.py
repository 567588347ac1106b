"""Cam profile synthesis by instant centres (Eqs. 1-21), for all four followers.

One signed-radius formulation serves rollers and concave faces alike. A follower
face is a circle of signed radius ``r`` (roller: r = r_c > 0; concave face:
r = r_f < 0) whose centre C sits at ``(x_c, Y_C)`` in the world frame X-Y of
Fig. 2 (origin at the cam axis O2, Y along the follower's motion):

    Y_C(theta) = y0 + S(theta),   y0 = sigma * sqrt((r + r_b)^2 - x_c^2)   (Eq. 3)

with sigma = sign(r + r_b): +1 for a roller (centre above the cam), -1 for a
concave face (centre below the axis, the face wrapping the cam; the paper's
L(theta) is -Y_C). The instant centre I23 = Q lies on the X axis at X = -V(theta)
for the clockwise cam (Eqs. 1-4), and the common normal passes through Q and C:

    n = sigma * (x_c + V, Y_C) / |(x_c + V, Y_C)|                           (Eqs. 5, 13)

so the contact point is A = C - r n (Eqs. 6-10, 14-18), and the body-fixed
profile is R(theta) A with the rotation of Eq. 11 (Eqs. 12, 19). For the paper's
double-concave follower this reproduces Eqs. 12 and 19 term by term (tested).

Which face drives which segment: the rising flank approaches from the left for
a clockwise cam, so the rise is driven by the face touching left of the stem
(x_c = -sigma e: the paper's S1 with its centre C1 on the right, or the left
roller), the fall by its mirror image (S2). Single followers have one face with
x_c = 0. The pressure angle is reported with the usual textbook sign
phi = atan((V + x_c) / |Y_C|): Eq. 5 on the rise and minus Eq. 13 on the fall
(the paper quotes the fall angle as a positive magnitude).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .model import MM, Design
from .motion import FALL, HIGH, LOW, RISE, Program, boundaries_rad


@dataclass(frozen=True)
class Face:
    """One follower face or roller: signed radius r [m], centre abscissa x_c [m]."""

    name: str
    r: float
    x_c: float


@dataclass(frozen=True)
class Geometry:
    """Closed-form geometry of a design (Eqs. 3, 20, 23, 25)."""

    faces: tuple[Face, ...]  # (rise face, fall face); one face for single followers
    r: float  # signed follower radius [m]
    r_b: float  # base radius [m]
    e: float  # offset [m]
    h: float  # lift [m]
    sigma: float
    y0: float  # Y_C at S = 0 [m] (Eq. 3 with S = 0; the paper's -L(0))
    dwell_radius: float  # R of the high-dwell arc [m] (Eq. 20)
    psi_h: float  # [rad] (Eq. 23)
    psi_l: float  # [rad] (Eq. 25)


def geometry(design: Design) -> Geometry:
    f = design.follower
    r, e = f.radius_mm * MM, f.effective_offset_mm * MM
    r_b, h = design.cam.base_radius_mm * MM, design.motion.lift_mm * MM
    sigma = 1.0 if r + r_b > 0 else -1.0
    if f.kind.is_double:
        tag = "roller" if f.kind.is_roller else "face"
        faces = (Face(f"S1 (left {tag})", r, -sigma * e), Face(f"S2 (right {tag})", r, sigma * e))
    else:
        faces = (Face("roller" if f.kind.is_roller else "face", r, 0.0),)
    y0 = sigma * math.sqrt((r + r_b) ** 2 - e**2)
    R = dwell_radius(r, r_b, e, h)
    return Geometry(
        faces=faces, r=r, r_b=r_b, e=e, h=h, sigma=sigma, y0=y0, dwell_radius=R,
        psi_h=psi(e, R, r), psi_l=psi(e, r_b, r),
    )


def dwell_radius(r: float, r_b: float, e: float, h: float) -> float:
    """Radius R of the high-dwell arc [m] (Eq. 20, generalized to signed r).

    The face centre at full lift is |C_h| = sqrt(e^2 + (y0 + h)^2) from the axis and
    R = sigma |C_h| - r. For a concave face (sigma = -1, r = r_f) this is Eq. 20:
    R = |r_f| - sqrt((r_f + r_b)^2 - 2 h sqrt((r_f + r_b)^2 - e^2) + h^2).
    """
    sigma = 1.0 if r + r_b > 0 else -1.0
    y0 = sigma * math.sqrt((r + r_b) ** 2 - e**2)
    return sigma * math.hypot(e, y0 + h) - r


def psi(e: float, radius: float, r: float) -> float:
    """Half the angle between the two contact points on a dwell arc [rad].

    psi = asin(e / |radius + r|): Eq. 23 with radius = R, Eq. 25 with radius = r_b
    (for r = r_f < 0, |R + r_f| = -R - r_f as printed). Zero for single followers.
    """
    return math.asin(min(1.0, e / abs(radius + r)))


@dataclass(frozen=True)
class FaceContact:
    """Where one face would touch the cam at each cam angle (world frame, metres)."""

    normal: np.ndarray  # (N, 2) unit common normal n, pointing from cam into follower
    point: np.ndarray  # (N, 2) contact point A = C - r n (Eqs. 10, 18)
    pressure_angle: np.ndarray  # phi [rad], signed, atan((V + x_c)/|Y_C|) (Eqs. 5, 13)


def face_contact(geo: Geometry, face: Face, prog: Program) -> FaceContact:
    """Contact point and normal of ``face`` for the program ``prog`` (Eqs. 3-10, 13-18)."""
    yc = geo.y0 + prog.S
    ux, uy = face.x_c + prog.V, yc
    m = np.hypot(ux, uy)
    n = geo.sigma * np.stack([ux, uy], axis=-1) / m[:, None]
    point = np.stack([face.x_c - face.r * n[:, 0], yc - face.r * n[:, 1]], axis=-1)
    phi = np.arctan2(geo.sigma * n[:, 0], n[:, 1])
    return FaceContact(n, point, phi)


def to_body(theta: np.ndarray, world: np.ndarray) -> np.ndarray:
    """World X-Y to cam-fixed x-y (Eq. 11): [x, y] = R(theta) [X, Y]."""
    c, s = np.cos(theta), np.sin(theta)
    return np.stack([c * world[:, 0] - s * world[:, 1], s * world[:, 0] + c * world[:, 1]], -1)


def curvature_radius(geo: Geometry, face: Face, prog: Program) -> np.ndarray:
    """Signed radius of curvature rho [m] of the profile traced by ``face`` (Eq. 21).

    Uses exact derivatives of the body-frame profile p = R(theta) A(theta):
    p' = R (J A + A'), p'' = R (-A + 2 J A' + A''), J = rotation by +90 deg, with
    A' and A'' from S, V, A(theta) and the jerk. rho > 0 where the cam is convex.
    """
    V, Ac, Jk = prog.V, prog.A, prog.J
    yc = geo.y0 + prog.S
    u = np.stack([face.x_c + V, yc], -1)
    du = np.stack([Ac, V], -1)
    ddu = np.stack([Jk, Ac], -1)
    m = np.hypot(u[:, 0], u[:, 1])[:, None]
    udu = np.sum(u * du, -1, keepdims=True)
    dm = udu / m
    ddm = (np.sum(du * du, -1, keepdims=True) + np.sum(u * ddu, -1, keepdims=True)) / m - (
        udu**2 / m**3
    )
    s = geo.sigma
    n = s * u / m
    dn = s * (du / m - u * dm / m**2)
    ddn = s * (ddu / m - 2 * du * dm / m**2 - u * ddm / m**2 + 2 * u * dm**2 / m**3)
    zero = np.zeros_like(V)
    A = np.stack([face.x_c + zero, yc], -1) - face.r * n
    dA = np.stack([zero, V], -1) - face.r * dn
    ddA = np.stack([zero, Ac], -1) - face.r * ddn
    rot = np.array([[0.0, -1.0], [1.0, 0.0]])
    p1 = A @ rot.T + dA
    p2 = -A + 2 * dA @ rot.T + ddA
    cross = p1[:, 0] * p2[:, 1] - p1[:, 1] * p2[:, 0]
    speed = np.hypot(p1[:, 0], p1[:, 1])
    with np.errstate(divide="ignore"):
        return np.where(cross == 0, np.inf, speed**3 / cross)


def contact_windows(geo: Geometry, prog: Program, design: Design) -> np.ndarray:
    """(n_faces, N) bool: which face touches the cam at each cam angle.

    Rise: the rise face. Fall: the fall face. Dwells of a single follower: its face.
    Dwells of a double follower (Sec. 4, Fig. 4): on the high arc the rise face
    touches from theta_1 = beta_r to theta_3 = beta_r + beta_h - 2 psi_h and the fall
    face from theta_2 = beta_r + 2 psi_h to theta_4 = beta_r + beta_h; both touch in
    between. (The paper prints theta_3 = beta_r + beta_h + 2 psi_h, which would put
    station 3 after station 4; its own geometry - A3 = B4 and Eq. 24 - gives the
    minus sign.) On the low arc both faces touch for the whole low dwell, from
    station 5 to station 0 (Eq. 26).
    """
    seg, th = prog.segment, prog.theta
    if len(geo.faces) == 1:
        return np.ones((1, th.size), dtype=bool)
    t1, t2, t3, _ = boundaries_rad(design)
    high, low = seg == HIGH, seg == LOW
    on_base = low | (th == 0) | (th == t3)  # stations 0 and 5 included
    rise_face = (seg == RISE) | on_base | (high & (th <= t2 - 2 * geo.psi_h))
    fall_face = ((seg == FALL) & (th != t3)) | on_base | (high & (th >= t1 + 2 * geo.psi_h))
    return np.stack([rise_face, fall_face])


def profile_part(geo: Geometry, prog: Program) -> np.ndarray:
    """(n_faces, N): the profile segment each face's contact point lies on.

    It is the motion segment, except where a double follower's idle face rests on
    the base circle at the ends of the rise or fall (stations 0 and 5): that point
    belongs to the low-dwell arc.
    """
    parts = np.repeat(prog.segment[None, :], len(geo.faces), axis=0)
    if len(geo.faces) == 2:
        parts[0][prog.segment == FALL] = LOW
        parts[1][prog.segment == RISE] = LOW
    return parts


@dataclass(frozen=True)
class Polyline:
    """The closed cam profile in the cam-fixed frame [m], in traversal order."""

    points: np.ndarray  # (M, 2)
    part: np.ndarray  # (M,) RISE / HIGH / FALL / LOW: the profile segment of each vertex
    theta: np.ndarray  # (M,) cam angle [rad] at which the vertex is a contact point

    @property
    def area(self) -> float:
        """Enclosed area [m^2] (shoelace)."""
        x, y = self.points[:, 0], self.points[:, 1]
        return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))

    @property
    def perimeter(self) -> float:
        d = np.diff(self.points, axis=0, append=self.points[:1])
        return float(np.hypot(d[:, 0], d[:, 1]).sum())

    def is_star_shaped(self) -> bool:
        """True if the polar angle about the cam axis strictly increases once around."""
        ang = np.unwrap(np.arctan2(self.points[:, 1], self.points[:, 0]))
        return bool(np.all(np.diff(ang) > 0) and ang[-1] - ang[0] < 2 * math.pi)


def assemble(prog: Program, body_points: np.ndarray, windows: np.ndarray,
             parts: np.ndarray) -> Polyline:
    """The profile as the union of every contact point over the cycle, in traversal order.

    Order: rise curve (by cam angle), high arc (by polar angle), fall curve (by cam
    angle), low arc (by polar angle, measured from the start of the rise). Every
    analysed cam angle thus has its contact point(s) as exact vertices, which lets
    the geometric check (camcore.verify) measure the synthesis to round-off.
    """
    P = body_points[windows]
    part = parts[windows]
    theta = np.broadcast_to(prog.theta, windows.shape)[windows]
    a0 = math.atan2(body_points[0, 0, 1], body_points[0, 0, 0])  # A0, theta = 0
    polar = np.mod(np.arctan2(P[:, 1], P[:, 0]) - a0, 2 * math.pi)
    on_arc = (part == HIGH) | (part == LOW)
    order = np.lexsort((np.where(on_arc, polar, theta), part))
    P, part, theta = P[order], part[order], theta[order]
    step = np.hypot(*np.diff(P, axis=0, append=P[:1]).T)
    keep = step > 1e-12 * max(1.0, float(np.abs(P).max()))
    return Polyline(P[keep], part[keep], theta[keep])
