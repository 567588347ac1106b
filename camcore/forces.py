"""Follower forces with guide friction (Section 5, Eqs. 29-41).

One contact (rise, fall, and the one-contact dwell windows): the unknowns are the
guide reactions F1 (lower end of the guide), F2 (upper end) and the contact force
F_N. Each guide reaction presses on the stem from one wall; which wall is the
contact *mode* of Fig. 6. With side s_i = +1 for the right wall (reaction in -X)
and -1 for the left wall, friction opposing the follower's velocity (sign sv),
and moments taken about the face centre C (through which F_N acts):

    sum F_x:  -s1 F1 - s2 F2 + n_x F_N = 0                                 (Eqs. 33, 39)
    sum F_y:  -sv mu (F1 + F2) + n_y F_N = F_t                              (Eqs. 34, 40)
    sum M_C:  sum_i [ s_i arm_i - sv mu (s_i d/2 - x_c) ] F_i = -x_c F_t     (Eqs. 35, 41)

with arm_1 = l1 - r, arm_2 = l1 + l2 - r. Mode (a) of Fig. 6 is (s1, s2) = (+1, -1),
for which these are Eqs. 33-35 (rise, x_c = e, sv = +1) and Eqs. 39-41 (fall,
x_c = -e, sv = -1) term by term. Modes are tried in the order (a) (+1,-1),
(b) (-1,+1), (c) (+1,+1), (d) (-1,-1) until F1, F2 >= 0, as the paper prescribes,
and F_N has the sign of F_t (our addition: the paper's example never meets a mode
that balances with F_N against F_t, which is the guide's friction wedging the
follower, not a balance; a short, wide guide with high friction does); if none
qualifies the guide self-locks (reported as a violation where F_t > 0, mode -1).

Two contacts (double followers in a dwell): Eqs. 36-38 give F1 = F2 = 0 and
F_N = F_t / (2 cos psi) at each contact.

Choices where the paper is silent (documented in the README, changeable in the
design): weight adds to the load (Eq. 29 with g along the follower axis), the
overhang shrinks as the follower rises (l1 = l1_0 - S), and friction is zero while
the follower is at rest (sv = 0 when V = 0).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .model import MM, Design, omega_rad_s
from .units import GRAM

MODES = ((1.0, -1.0), (-1.0, 1.0), (1.0, 1.0), (-1.0, -1.0))
V_REST = 1e-12  # [m/rad]: |V| below this is the follower at rest (1 pm per radian)
TWO_CONTACTS = 4  # mode code of a two-contact dwell (Eqs. 36-38); -1 = self-locking


def moving_mass(design: Design) -> float:
    """m = M + m_s / 3 [kg]: the follower's mass M and a third of the return spring's
    own mass m_s (a uniform spring's kinetic energy is that of a third of its mass
    moving with its free end: Rayleigh; Norton, Cam Design and Manufacturing Handbook,
    ch. 8). The paper's M of Eq. 29 when the spring's mass is 0 (its example); the
    rigid model, the jump speed and the elastic train (camcore.train) all use it, so
    they agree on when the follower leaves the cam."""
    d = design.dynamics
    return (d.mass_g + d.spring_mass_g / 3.0) * GRAM


def inertia_load(design: Design, A: np.ndarray) -> np.ndarray:
    """m (g + a) with a = A omega^2 and m = moving_mass [N]: the part of Eq. 29 the
    spring must overcome."""
    d = design.dynamics
    return moving_mass(design) * (d.gravity_m_s2 + A * omega_rad_s(design) ** 2)


def spring_load(design: Design, S: np.ndarray) -> np.ndarray:
    """k s with s = S + s_p [N]: the spring's part of Eq. 29 (Eq. 30)."""
    d = design.dynamics
    return d.spring_rate_N_per_m * (S + d.preload_mm * MM)


def external_load(design: Design) -> float:
    """F_e [N]: dynamics.external_load_N, a constant load along the follower's axis
    toward the cam (beyond the paper, whose F_t has only weight, inertia and spring:
    F_e adds to it as M g does, so every formula that holds for the weight holds)."""
    return design.dynamics.external_load_N


def total_load(design: Design, S: np.ndarray, A: np.ndarray) -> np.ndarray:
    """F_t = M (g + a) + k s + F_e with a = A omega^2 and s = S + s_p  [N] (Eqs. 29-30;
    F_e = external_load, 0 in the paper)."""
    return inertia_load(design, A) + spring_load(design, S) + external_load(design)


@dataclass(frozen=True)
class GuideSolution:
    F1: np.ndarray  # [N], >= 0 in the chosen mode
    F2: np.ndarray  # [N]
    FN: np.ndarray  # [N] contact force per contact
    mode: np.ndarray  # index into MODES, -1 where no mode balances (self-locking)
    side1: np.ndarray  # s1 of the chosen mode (+1 right wall, -1 left wall, 0 none)
    side2: np.ndarray


def _solve_mode(s1, s2, mu_sv, normal, Ft, x_c, arm1, arm2, d, slide=0.0, moment=0.0):
    """(F1, F2, FN) of the equilibrium for guide sides (s1, s2), batched over angles.

    The cam pushes with F_N along D = n + slide t (t = (n_y, -n_x) the tangent; slide =
    mu_c sigma, the contact friction, 0 in the paper), and ``moment`` F_N is its moment
    about the reference point C beyond that of a force through C (a friction force at
    the contact point A = C - r n adds r slide). D_y > 0 (the force points into the
    follower), so sum F_y gives F_N = (F_t + mu_sv (F1 + F2)) / D_y; substituting into
    sum F_x and sum M_C leaves two linear equations in F1, F2, solved by Cramer's rule.
    """
    if np.ndim(slide) == 0 and slide == 0.0:  # the paper: D = n (the same numbers, faster)
        Dx, Dy = normal[:, 0], normal[:, 1]
    else:
        Dx, Dy = normal[:, 0] + slide * normal[:, 1], normal[:, 1] - slide * normal[:, 0]
    t = Dx / Dy
    a, b = t * mu_sv - s1, t * mu_sv - s2
    m1 = s1 * arm1 - mu_sv * (s1 * d / 2 - x_c)
    m2 = s2 * arm2 - mu_sv * (s2 * d / 2 - x_c)
    xq = x_c
    if not (np.ndim(moment) == 0 and moment == 0.0):
        q = moment / Dy
        m1, m2, xq = m1 + q * mu_sv, m2 + q * mu_sv, x_c + q
    det = a * m2 - b * m1
    with np.errstate(divide="ignore", invalid="ignore"):
        F1 = Ft * (b * xq - t * m2) / det
        F2 = Ft * (t * m1 - a * xq) / det
        FN = (Ft + mu_sv * (F1 + F2)) / Dy
    return F1, F2, FN


def _first_mode(design: Design, Ft, normal, x_c, r, S, V, slide, moment) -> GuideSolution:
    """Solve in the modes of Fig. 6 and keep the first with F1, F2 >= 0 and F_N of F_t's
    sign (else the guide wedges the follower, F_N growing without F_t): each mode is
    solved only at the angles no earlier mode balanced (one or two modes hold almost
    everywhere: on the paper example's rise it is (b) at every angle, the printed
    Eqs. 33-35 giving F1, F2 < 0; so this is about two solves, not four)."""
    dyn = design.dynamics
    d = dyn.guide_width_mm * MM
    l1 = dyn.overhang_mm * MM - (S if dyn.overhang_shrinks else 0.0)
    arm1, arm2 = l1 - r, l1 + dyn.guide_length_mm * MM - r
    # no friction while the follower is at rest, round-off included (a law's V at its
    # own end is 1e-18 m/rad either side of 0: its sign had flipped the friction there)
    mu_sv = dyn.guide_friction * np.sign(np.where(np.abs(V) < V_REST, 0.0, V))
    tol = 1e-9 * (np.abs(Ft) + 1.0)
    todo = None  # the angles without a mode yet (None: all of them)
    for i, (s1, s2) in enumerate(MODES):
        mu, nrm, F, xc, a1, a2, sl, mo, tl = (
            at_(x, todo) for x in (mu_sv, normal, Ft, x_c, arm1, arm2, slide, moment, tol)
        )
        F1, F2, FN = _solve_mode(s1, s2, mu, nrm, F, xc, a1, a2, d, sl, mo)
        # F_N against F_t (F1, F2 >= 0 notwithstanding) is the guide's friction wedging
        # the follower: self-locking, not a balance (a physics review: mode (a) with
        # F_N = -191 N at F_t = +126 N was taken for a jump, mode (b) balancing there)
        ok = np.isfinite(FN) & (F1 >= -tl) & (F2 >= -tl) & (FN * np.sign(F) >= -tl)
        if todo is None:  # mode (a) everywhere; replaced below where it does not hold
            out, mode = [F1, F2, FN], np.where(ok, 0, -1).astype(np.int8)
            todo = np.flatnonzero(~ok)
        else:
            for o, v in zip(out, (F1, F2, FN), strict=True):
                o[todo[ok]] = v[ok]
            mode[todo[ok]] = i
            todo = todo[~ok]
        if not todo.size:
            break
    assert todo is not None  # (the loop ran)
    if todo.size:
        # Self-locking guide: no mode balances with friction. Keep finite numbers (the
        # frictionless solution, whose signed guide forces pick the walls) and let the
        # checks report the violation.
        nrm, F, xc, a1, a2 = (at_(x, todo) for x in (normal, Ft, x_c, arm1, arm2))
        G1, G2, GN = _solve_mode(1.0, -1.0, 0.0, nrm, F, xc, a1, a2, d)
        for o, v in zip(out, (np.abs(G1), np.abs(G2), GN), strict=True):
            o[todo] = v
    sides = np.array(MODES + ((0.0, 0.0),))[mode]
    return GuideSolution(
        np.maximum(out[0], 0.0), np.maximum(out[1], 0.0), out[2], mode, sides[:, 0], sides[:, 1]
    )


def jammed(g: GuideSolution) -> np.ndarray:
    """Where the guide jams: no mode balances (mode -1) and F_t > 0 (the frictionless
    F_N kept there has F_t's sign; where F_t < 0 the follower jumps instead). The one
    rule of checks, the batched core and the search between the samples."""
    return (g.mode < 0) & (g.FN > 0)


def at_(x, idx):
    """x at the angles ``idx`` if x is per angle (None: all angles; a scalar stays)."""
    return x if idx is None or np.ndim(x) == 0 else x[idx]


def one_contact(design: Design, Ft, normal, x_c, r, S, V, slide=0.0) -> GuideSolution:
    """Eqs. 33-35 / 39-41 in the modes of Fig. 6, moments about the face centre C;
    ``slide`` = mu_c sigma tilts the contact force (contact friction, see _solve_mode)."""
    return _first_mode(design, Ft, normal, x_c, r, S, V, slide, r * slide)


def two_contacts(Ft, normal) -> GuideSolution:
    """Eqs. 36-38: symmetric dwell contact, F1 = F2 = 0 and F_N = F_t / (2 cos psi)."""
    zero = np.zeros_like(Ft)
    FN = Ft / (2.0 * normal[:, 1])
    mode = np.full(Ft.shape, TWO_CONTACTS, np.int8)
    return GuideSolution(zero, zero.copy(), FN, mode, zero, zero)


def two_contacts_with_friction(design: Design, Ft, normal, x_c, r, S, V, slide) -> GuideSolution:
    """Both faces on a dwell arc with contact friction: the cam drags both faces the same
    way, so the guide must hold the follower (F1, F2 > 0). The paper's equal sharing of
    the load (Eqs. 36-38) is kept; moments about the axis point between the face
    centres: each face's force F_N D_k acts through C_k at lever x_c,k, plus its
    friction moment r slide_k."""
    D = normal + slide[..., None] * np.stack([normal[..., 1], -normal[..., 0]], axis=-1)
    total = D.sum(axis=0)  # per unit F_N: both faces
    moment = (x_c * D[..., 1] + r * slide).sum(axis=0)
    # the one-contact solver with a virtual contact of unit direction u = total / |total|
    # through the axis point: its force F' u is the faces' F_N total, so F_N = F' / |total|
    scale = np.hypot(total[:, 0], total[:, 1])
    g = _first_mode(
        design, Ft, total / scale[:, None], np.zeros_like(Ft), r, S, V, 0.0, moment / scale
    )
    mode = np.where(g.mode >= 0, TWO_CONTACTS, -1).astype(np.int8)
    return GuideSolution(g.F1, g.F2, g.FN / scale, mode, g.side1, g.side2)


def tangential_slip(point_world, normal, V) -> np.ndarray:
    """t . (v_cam - v_follower) / w [m/rad], (F, N): how fast the cam surface slides past
    a face fixed to the follower, along the tangent t = (n_y, -n_x) at each contact,
    per unit cam speed. v_cam = w (p_y, -p_x) (clockwise cam), v_follower = (0, V w).
    Its sign sigma orients the contact friction (the cam drags the face along sigma t);
    its size is the sliding speed of camcore.wear."""
    rel_x, rel_y = point_world[..., 1], -point_world[..., 0] - V
    return normal[..., 1] * rel_x - normal[..., 0] * rel_y


def follower_forces(
    design: Design, Ft, in_contact, normal, x_c, r, S, V, slide=None
) -> GuideSolution:
    """Guide and contact forces at each cam angle for the faces in contact.

    in_contact, normal : (n_faces, N) and (n_faces, N, 2); x_c : (n_faces, N) [m], the
    lever of each face's contact force from the follower's axis (profile.lever_x).
    r : the face radius to the guide arms [m], a scalar or per angle (N,) (camcore.batch
    lays many designs along the angle axis).
    slide : (n_faces, N) mu_c sigma per face (contact friction), or None (the paper).
    Both faces touching: Eqs. 36-38. One face: Eqs. 33-35 / 39-41 with that face's
    normal and centre. No face (a broken high dwell, Eq. 28): all forces zero.
    """
    lead = np.where(in_contact[0], 0, in_contact.shape[0] - 1)
    idx = np.arange(Ft.size)
    friction = slide is not None and np.any(slide)
    sl = slide[lead, idx] if friction else 0.0
    one = one_contact(design, Ft, normal[lead, idx], x_c[lead, idx], r, S, V, sl)
    if friction and in_contact.shape[0] == 2:
        two = two_contacts_with_friction(design, Ft, normal, x_c, r, S, V, slide)
    else:
        two = two_contacts(Ft, normal[0])
    both = in_contact.all(axis=0) & (in_contact.shape[0] == 2)
    touching = in_contact.any(axis=0)

    def pick(name):
        return np.where(both, getattr(two, name), getattr(one, name))

    F1, F2, FN = (np.where(touching, pick(k), 0.0) for k in ("F1", "F2", "FN"))
    return GuideSolution(F1, F2, FN, pick("mode"), pick("side1"), pick("side2"))


def contact_direction(normal: np.ndarray, slide) -> np.ndarray:
    """D = n + slide t (F, N, 2): the cam's force on a face per unit F_N."""
    t = np.stack([normal[..., 1], -normal[..., 0]], axis=-1)
    return normal + np.asarray(slide)[..., None] * t


def cam_torque(point_world: np.ndarray, normal: np.ndarray, FN: np.ndarray) -> np.ndarray:
    """Torque [N m] each contact asks of the cam shaft, positive when the shaft drives.

    The cam pushes the follower with F = F_N n at the contact point p (world frame).
    With the shaft at constant speed and the cam's own inertia aside, the shaft torque
    balances the follower's reaction: T_z = (p x F)_z about the cam centre O. The cam
    turns clockwise (-z, see profile.to_body), so the torque that *drives* it is
    T = -(p x F)_z. Without friction at the contact this equals F_N n_y V (the power
    F_N n_y V omega given to the follower; the normal passes through I23 at OI23 = V,
    Eqs. 1-4), which the tests use as the independent check.

    point_world, normal : (F, N, 2); FN : (F, N) -> (F, N), zero where a face is idle.
    With contact friction pass the force direction D (contact_direction) as ``normal``.
    """
    cross = point_world[..., 0] * normal[..., 1] - point_world[..., 1] * normal[..., 0]
    return -FN * cross
