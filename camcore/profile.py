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

from .model import Design
from .motion import FALL, REST_TOL_M, RISE, Program, Segment
from .units import MM

MIN_OFFSET = 1e-12  # [m] offsets below this are 0: the faces coincide


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
    r: float  # signed follower radius [m]: +inf flat face, 0 knife edge
    r_b: float  # base radius [m]
    e: float  # offset of the two faces of a double follower [m] (0 for singles)
    h: float  # lift [m]
    sigma: float
    y0: float  # Y_C at S = 0 [m] (Eq. 3 with S = 0; the paper's -L(0)); r_b for a flat face
    dwell_radius: float  # R of the high-dwell arc [m] (Eq. 20)
    psi_h: float  # [rad] (Eq. 23)
    psi_l: float  # [rad] (Eq. 25)
    stem_x: float = 0.0  # world X of the follower's axis [m] (a single follower's offset)

    @property
    def flat(self) -> bool:
        """A flat face (r = +inf): the contact lies where the face meets the normal
        through the instant centre, X = -V, not below a centre."""
        return math.isinf(self.r)


def geometry(design: Design) -> Geometry:
    """The closed-form geometry of ``design``.

    A double follower with e = 0 is a valid, degenerate design: its two faces coincide,
    so it is one face on the stem centreline (nothing to share the load with). A single
    follower sits on its axis at X = stem_x (offset e_s, positive to the left). A flat
    face is a line at Y = r_b + S; a knife edge is a roller of radius 0.
    """
    f = design.follower
    r, e = f.radius_mm * MM, abs(f.effective_offset_mm) * MM  # abs: -0.0 mm is 0
    if e < MIN_OFFSET:  # a picometre is no offset (and a denormal one underflows psi)
        e = 0.0
    r_b, h = design.cam.base_radius_mm * MM, design.motion.lift_mm * MM
    stem_x = f.stem_x_mm * MM
    sigma = 1.0 if r + r_b > 0 else -1.0
    tag = "roller" if f.kind.is_roller else "face" if f.kind.is_concave else f.kind.label
    faces: tuple[Face, ...]
    if f.kind.is_double and e > 0:
        faces = (Face(f"S1 (left {tag})", r, -sigma * e), Face(f"S2 (right {tag})", r, sigma * e))
    elif f.kind.is_double:
        faces = (Face(f"S1 = S2 ({tag}s coincide, e = 0)", r, 0.0),)
    else:
        faces = (Face(tag, r, stem_x),)
    x = max(e, abs(stem_x))
    if math.isinf(r):  # flat face: no centre; the face itself rises from r_b
        y0, R = r_b, r_b + h
    else:
        y0 = sigma * math.sqrt((r + r_b) ** 2 - x**2)
        R = dwell_radius(r, r_b, x, h)
    return Geometry(
        faces=faces,
        r=r,
        r_b=r_b,
        e=e,
        h=h,
        sigma=sigma,
        y0=y0,
        dwell_radius=R,
        psi_h=psi(e, R, r),
        psi_l=psi(e, r_b, r),
        stem_x=stem_x,
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
    if e == 0.0:
        return 0.0
    return math.asin(min(1.0, e / abs(radius + r)))


@dataclass(frozen=True)
class FaceContact:
    """Where one face would touch the cam at each cam angle (world frame, metres)."""

    normal: np.ndarray  # (N, 2) unit common normal n, pointing from cam into follower
    point: np.ndarray  # (N, 2) contact point A = C - r n (Eqs. 10, 18)
    pressure_angle: np.ndarray  # phi [rad], signed, atan((V + x_c)/|Y_C|) (Eqs. 5, 13)


def face_contact(geo: Geometry, face: Face, prog: Program) -> FaceContact:
    """Contact point and normal of ``face`` for the program ``prog`` (Eqs. 3-10, 13-18).

    A flat face (r = inf) has the vertical normal everywhere: it passes through the
    instant centre Q at X = -V (Eqs. 1-4), so the contact is at (-V, r_b + S) and the
    pressure angle is 0 (the classic flat-faced follower, e.g. Norton, Cam Design and
    Manufacturing Handbook, ch. 7)."""
    yc = geo.y0 + prog.S
    if geo.flat:
        n = np.broadcast_to(np.array([0.0, 1.0]), (prog.S.size, 2)).copy()
        point = np.stack([-prog.V, yc], axis=-1)
        return FaceContact(n, point, np.zeros_like(prog.S))
    ux, uy = face.x_c + prog.V, yc
    m = np.hypot(ux, uy)
    n = geo.sigma * np.stack([ux, uy], axis=-1) / m[:, None]
    point = np.stack([face.x_c - face.r * n[:, 0], yc - face.r * n[:, 1]], axis=-1)
    phi = np.arctan2(geo.sigma * n[:, 0], n[:, 1])
    return FaceContact(n, point, phi)


def instant_centre(V: np.ndarray) -> np.ndarray:
    """I23 = Q [m], (N, 2) world frame: on the X axis at X = -V (Eqs. 1-4), where the
    common normal of every face crosses it."""
    V = np.asarray(V, dtype=float)
    return np.stack([-V, np.zeros_like(V)], axis=-1)


def face_centres(geo: Geometry, S: np.ndarray) -> np.ndarray:
    """Centre C of each face [m], (F, N, 2) world frame: (x_c, y0 + S) (Eq. 3); for a
    flat face the point of its plane on the face's axis."""
    S = np.asarray(S, dtype=float)
    return np.stack([np.stack([np.full_like(S, f.x_c), geo.y0 + S], axis=-1) for f in geo.faces])


def to_body(theta: np.ndarray, world: np.ndarray) -> np.ndarray:
    """World X-Y to cam-fixed x-y (Eq. 11): [x, y] = R(theta) [X, Y]."""
    c, s = np.cos(theta), np.sin(theta)
    return np.stack([c * world[:, 0] - s * world[:, 1], s * world[:, 0] + c * world[:, 1]], -1)


def pitch_curvature(geo: Geometry, face: Face, prog: Program) -> np.ndarray:
    """Signed curvature kappa_p [1/m] of the pitch curve, the path of the face centre C
    on the cam (cam frame), from S, V and A alone.

    C = (x_c, Y), Y = y0 + S, in the world frame is R(theta) C on the cam (Eq. 11), so
    with u = x_c + V the derivatives give the classic pitch-curve formula

        kappa_p = (Y^2 + u (u + V) - A Y) / (Y^2 + u^2)^(3/2)

    (1/kappa_p = r_b + r_c + S on a roller's dwell). Y^2 + u^2 > 0 for every design the
    model accepts (the face centre never reaches the cam axis), so kappa_p is finite.
    """
    Y = geo.y0 + prog.S
    if geo.flat:  # no pitch curve: the profile's own curvature, 1 / (r_b + S + S'')
        with np.errstate(divide="ignore"):
            return 1.0 / (Y + prog.A)
    u = face.x_c + prog.V
    return (Y * Y + u * (u + prog.V) - prog.A * Y) / (Y * Y + u * u) ** 1.5


def curvature_radius(geo: Geometry, face: Face, kappa_p: np.ndarray) -> np.ndarray:
    """Signed radius of curvature rho [m] of the cam profile at the contact (Eq. 21).

    The profile is the parallel curve at distance r of the pitch curve, so
    A flat face: rho = r_b + S + S'' (the classic closed form), whose reciprocal is
    its kappa_p. Otherwise
    rho = sigma / kappa_p - r (sigma = +1 roller, -1 concave face): cheaper than
    evaluating Eq. 21 on the traced profile, and right in sign where the profile folds
    back on itself, where the traced curve turns round and Eq. 21 flips sign (a roller
    with 0 < 1/kappa_p < r_c, a concave face with 1/kappa_p > |r_f|). rho > 0 where the
    cam is convex; +inf where the pitch curve is straight (kappa_p = 0).
    ``kappa_p`` is ``pitch_curvature(geo, face, prog)``.
    """
    r = 0.0 if geo.flat else face.r  # flat face: kappa_p is the profile's curvature
    with np.errstate(divide="ignore"):
        return np.where(kappa_p == 0.0, np.inf, geo.sigma / kappa_p - r)


def datum_radius(points: np.ndarray) -> float:
    """The profile's radius [m] on the cam frame's +Y ray (theta = 0: where the
    follower sits at theta = 0, the DXF's datum and the keyway's ray): that of the
    vertex of the closed profile ``points`` (M, 2) [m] nearest the ray."""
    k = int(np.argmin(np.abs(np.arctan2(points[:, 0], points[:, 1]))))
    return float(np.hypot(*points[k]))


def radius_extremes(rho: np.ndarray, in_contact: np.ndarray) -> tuple[float, float]:
    """(smallest convex rho > 0, tightest concave |rho| with rho < 0) [m] of the signed
    radii ``rho`` (curvature_radius, per face and angle) where a face touches; inf where
    the cam has no such stretch, and a straight pitch curve (inf) counts as neither.
    The report's radius_of_curvature_mm and the G-code's cutter advice."""
    r = rho[in_contact]
    r = r[np.isfinite(r)]
    convex, concave = r[r > 0], -r[r < 0]
    return (
        float(convex.min()) if convex.size else math.inf,
        float(concave.min()) if concave.size else math.inf,
    )


def lever_x(geo: Geometry, face: Face, prog: Program) -> np.ndarray:
    """Horizontal distance [m] from the follower's axis to the point through which the
    contact force acts, per cam angle: the face centre C (x_c - stem_x: +-e for double
    followers, 0 for a single one on its axis), or for a flat face the contact point
    itself, X = -V (the flat face's contact wanders across the face)."""
    if geo.flat:
        return -prog.V - geo.stem_x
    return np.full(prog.S.shape, face.x_c - geo.stem_x)


def face_sides(geo: Geometry) -> tuple[float, ...]:
    """World direction of each face's dwell contact, +1 left of the stem, -1 right.

    The rise face S1 touches left of the stem (its centre is on the right for a concave
    face), the fall face S2 right; a single face sits on the centreline (0).
    """
    return (1.0, -1.0) if len(geo.faces) == 2 else (0.0,)


def dwell_psi(geo: Geometry, S: float) -> float:
    """psi [rad] of a dwell at displacement S: half the angle its two contacts subtend
    (Eqs. 23, 25 at the dwell's own radius); 0 for single followers."""
    if len(geo.faces) == 1:
        return 0.0
    return math.asin(min(1.0, geo.e / math.hypot(geo.e, geo.y0 + S)))


def arc_span(geo: Geometry, segs: tuple[Segment, ...], j: int) -> tuple[float, float]:
    """Cam-frame polar interval [start, end] [rad, relative to the cam angle] that the
    dwell arc of segment j occupies, in j's own frame: the arc of the whole run of
    dwells j belongs to (``dwell_run``; one dwell, usually).

    A face at world side s (+1 left) touches the cam at direction s psi from vertical,
    i.e. at cam-frame angle theta + s psi. The arc starts where the face driving the
    motion before the run left off and ends where the face driving the one after it
    takes over (rise: S1, fall: S2). Between a rise and a fall (the high dwell) this
    gives beta - 2 psi (Eq. 24), between a fall and a rise (the low dwell) beta + 2 psi
    (Eq. 26), and beta between two rises or two falls.
    """
    run = dwell_run(segs, j)
    psi_j = dwell_psi(geo, segs[j].S0)
    s_before = 1.0 if run.before.code == RISE else -1.0
    s_after = 1.0 if run.after.code == RISE else -1.0
    return run.t0 + s_before * psi_j, run.t1 + s_after * psi_j


@dataclass(frozen=True)
class DwellRun:
    """The run of consecutive dwells (also across theta = 0) at one displacement."""

    head: int  # the run's lowest segment index: the one its arc's contacts are put on
    t0: float  # the run's cam angles [rad] in the asking segment's frame (t0 < 0 or
    t1: float  # t1 > 2 pi where the run crosses theta = 0)
    before: Segment  # the motion before the run and the one after it
    after: Segment


def dwell_run(segs: tuple[Segment, ...], j: int) -> DwellRun:
    """The run of dwells segment j belongs to. The follower rests at one S throughout
    a run, so its faces touch one arc: a low dwell split at theta = 0 (a program that
    starts and ends with it) or two dwells in a row are one dwell to the geometry."""
    n, g = len(segs), segs[j]
    t0, t1, members = g.start, g.end, [j]
    ends = {}
    for step in (-1, 1):
        k = j
        for _ in range(n - 1):
            nxt = segs[(k + step) % n]
            if nxt.is_motion or abs(nxt.S0 - g.S0) > REST_TOL_M:
                break
            k += step
            members.append(k % n)
            if step < 0:
                t0 -= nxt.length
            else:
                t1 += nxt.length
        ends[step] = segs[(k + step) % n]
    return DwellRun(min(members), t0, t1, ends[-1], ends[1])


def dwell_runs(segs: tuple[Segment, ...]) -> dict[int, tuple[float, float]]:
    """Each run of dwells once: its head's index -> the run's cam angles [t0, t1]
    [rad] in the head's frame (see ``dwell_run``)."""
    out = {}
    for j, g in enumerate(segs):
        if not g.is_motion:
            run = dwell_run(segs, j)
            if run.head == j:
                out[j] = (run.t0, run.t1)
    return out


def contact_windows(
    geo: Geometry, prog: Program, segs: tuple[Segment, ...]
) -> tuple[np.ndarray, np.ndarray]:
    """Which face touches the cam at each cam angle, and on which profile segment.

    Returns (windows, part), both (n_faces, N): windows[i, k] is True where face i
    touches at prog.theta[k]; part[i, k] is the index (into ``segs``) of the profile
    segment face i's contact point lies on.

    A single face always touches. A double follower (Sec. 4, Fig. 4): every rise is
    driven by S1 and every fall by S2; on a dwell arc (see ``arc_span``) a face
    touches while its contact direction theta + s psi lies on the arc. For the paper's
    program this gives its stations: the rise face on the high arc from beta_r to
    beta_r + beta_h - 2 psi_h, the fall face from beta_r + 2 psi_h to beta_r + beta_h,
    and both faces for the whole low dwell. (The paper prints station 3 at
    beta_r + beta_h + 2 psi_h, after station 4; its own geometry - A3 = B4 and Eq. 24 -
    gives the minus sign.)
    """

    def arc(j: int) -> tuple[float, float, float]:
        return (*arc_span(geo, segs, j), dwell_psi(geo, segs[j].S0))

    return windows_on_arcs(prog, segs, len(geo.faces), arc)


def windows_on_arcs(prog: Program, segs: tuple[Segment, ...], n_faces: int, arc):
    """contact_windows given each dwell arc: ``arc(j)`` -> (start, end, psi) of segment
    j's arc, scalars or one value per angle (camcore.batch: many designs at once)."""
    N, F = prog.theta.size, n_faces
    part = np.repeat(prog.index[None, :], F, axis=0)
    if F == 1:
        return np.ones((1, N), dtype=bool), part
    driver = np.where(prog.segment == RISE, 0, np.where(prog.segment == FALL, 1, -1))
    windows = np.stack([driver == 0, driver == 1])
    tol, two_pi = 1e-12, 2 * math.pi
    for j, (t0, t1) in dwell_runs(segs).items():
        start, end, psi_j = arc(j)
        # the cam angle (in [0, 2 pi)) in the run's frame [t0, t0 + 2 pi): inside while
        # <= t1 (comparisons, not np.mod: this runs for every evaluation)
        if t0 >= 0.0:
            th = np.where(prog.theta < t0 - tol, prog.theta + two_pi, prog.theta)
        else:
            th = np.where(prog.theta >= t0 + two_pi - tol, prog.theta - two_pi, prog.theta)
        inside = th <= t1 + tol
        for i, side in enumerate((1.0, -1.0)):  # face_sides of a double follower
            # the contact's direction theta + s psi from the arc's start (it lies within
            # 2 psi before the run's start: a turn later, then)
            along = th + side * psi_j - start
            along = np.where(along < -tol, along + two_pi, along)
            on = inside & (along <= end - start + tol)
            windows[i] |= on
            part[i] = np.where(on & (driver != i), j, part[i])
    return windows, part


@dataclass(frozen=True)
class Polyline:
    """The closed cam profile in the cam-fixed frame [m], in traversal order."""

    points: np.ndarray  # (M, 2)
    part: np.ndarray  # (M,) RISE / HIGH / FALL / LOW: the profile segment of each vertex
    theta: np.ndarray  # (M,) cam angle [rad] at which the vertex is a contact point

    @property
    def area(self) -> float:
        """Enclosed area [m^2] (shoelace). Summed by numpy, not np.dot: BLAS sums in an
        order that depends on its threads, and a review found a sweep's Dask workers
        (one thread) 4e-14 apart from the same design's report."""
        x, y = self.points[:, 0], self.points[:, 1]
        return 0.5 * float(np.sum(x * np.roll(y, -1) - y * np.roll(x, -1)))

    @property
    def perimeter(self) -> float:
        d = np.diff(self.points, axis=0, append=self.points[:1])
        return float(np.hypot(d[:, 0], d[:, 1]).sum())

    def is_star_shaped(self) -> bool:
        """True if the polar angle about the cam axis strictly increases once around."""
        ang = np.unwrap(np.arctan2(self.points[:, 1], self.points[:, 0]))
        return bool(np.all(np.diff(ang) > 0) and ang[-1] - ang[0] < 2 * math.pi)


def assemble(
    prog: Program,
    segs: tuple[Segment, ...],
    body_points: np.ndarray,
    windows: np.ndarray,
    parts: np.ndarray,
    geo: Geometry,
) -> Polyline:
    """The profile as the union of every contact point over the cycle, in traversal order.

    ``parts`` holds segment indices (see ``contact_windows``: a run of dwells puts its
    arc's contacts on its head). Order: segment by segment as the program runs; within
    a rise or fall by cam angle, within a dwell arc by the contact's direction theta +
    s psi (face side s, ``face_sides``), theta taken in the run's frame: the contacts
    sweep the arc that way, whether it reaches across theta = 0 (a program that starts
    with a dwell, a double follower's low dwell arc from -psi) or, for an offset single
    follower, sits a few degrees beside theta + pi/2. Every analysed cam angle thus
    has its contact point(s) as exact vertices.
    """
    P = body_points[windows]
    index = parts[windows]
    theta = np.broadcast_to(prog.theta, windows.shape)[windows]
    side = np.broadcast_to(np.array(face_sides(geo))[:, None], windows.shape)[windows]
    t0, psi = np.zeros(len(segs)), np.zeros(len(segs))  # each dwell's frame and psi
    for j, g in enumerate(segs):
        if not g.is_motion:
            t0[j], psi[j] = dwell_run(segs, j).t0, dwell_psi(geo, g.S0)
    # (1e-12 rad of slack: a contact at the run's start stays at its start)
    lifted = t0[index] + np.mod(theta - t0[index] + 1e-12, 2 * math.pi) - 1e-12
    motion = np.array([g.is_motion for g in segs])[index]
    start = np.array([g.start for g in segs])[index]  # a last motion ends at 0 = 2 pi
    along = np.where(theta < start - 1e-12, theta + 2 * math.pi, theta)
    key = np.where(motion, along, lifted + side * psi[index])
    order = np.lexsort((key, index))
    P, index, theta, motion = P[order], index[order], theta[order], motion[order]
    # a point reached twice (where an arc meets a curve, B2 = A1, A3 = B4, ...) is kept
    # once, as the end of the rise or fall curve
    step = np.hypot(*np.diff(P, axis=0, append=P[:1]).T)
    pair = step <= 1e-12 * max(1.0, float(np.abs(P).max()))  # P[i] == P[i + 1]
    drop = (pair & ~motion) | np.roll(pair & motion, 1)
    keep = ~drop if not drop.all() else np.arange(P.shape[0]) == 0
    codes = np.array([g.code for g in segs], dtype=np.int8)
    return Polyline(P[keep], codes[index[keep]], theta[keep])
