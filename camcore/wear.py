"""Wear along the cam profile and the surface-fatigue (pitting) life (issue 11).

Not in the paper, which argues only that a lower contact stress means less wear. Here
that claim is made measurable.

Sliding wear (Archard): the depth worn at a point of a surface is dh = k p v_s dt, with
k the specific wear rate [m^2/N = m^3/(N m)], p the contact pressure and v_s the sliding
speed. A point of the cam surface spends 2b / u in the contact strip of half-width b
that crosses it at the speed u of the contact along the cam; the mean pressure over the
strip is F_N / (2 b w). So each pass of a face wears the cam point by

    h = k (F_N / w) (v_s / u)          [m per pass]

independent of the Hertz width: the Archard volume k F_N v_s dt spread over the strip.
With the cam turning at w, u = w ds/dtheta (camcore.sampling.contact_travel), and v_s
is the tangential speed of the cam surface relative to the follower's at the contact:

    v_s = | t . (v_cam(p) - v_follower) |,  v_cam(p) = w (p_y, -p_x)  (clockwise cam),
    v_follower = (0, V w)

for a face fixed to the follower (concave faces, flat face, knife edge). A roller rolls:
v_s = 0 and no sliding wear (its life is the pitting life below). On a dwell arc the
follower rests and the cam slides under the face: v_s / u = 1.

Pitting: a contact-stress life curve N = N_ref (sigma_allow / sigma_max)^m through the
allowable contact stress at N_ref cycles (model.Wear; m = 13.2 after ISO 6336-2 for
case-hardened steel). A rough estimate for comparison, not a guarantee.
"""

from __future__ import annotations

import math

import numpy as np

from .extremes import peak
from .forces import tangential_slip
from .model import allowable_contact_stress_MPa, omega_rad_s
from .sampling import contact_travel
from .units import MM, MPA

MM3_PER_N_M = 1e-9  # m^3/(N m) per mm^3/(N m)


def sliding_ratio(a, geo=None) -> np.ndarray:
    """v_s / u per face (F, N): sliding speed over the contact's speed along the cam
    (dimensionless, speed-independent); 0 for rollers, NaN where the contact does not
    move along the cam (u = 0). ``a``: an Analysis, or a Local with its ``geo``."""
    geo = a.geo if geo is None else geo
    if _rolls(geo):
        return np.zeros(a.FN.shape)
    vs = np.abs(tangential_slip(a.point_world, a.normal, a.prog.V))
    u = contact_travel(a, geo)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(u > 0, vs / u, np.nan)


def _rolls(geo) -> bool:
    """Rollers roll: no sliding wear."""
    return geo.r > 0 and not geo.flat


def depth_per_pass(a, design=None, geo=None) -> np.ndarray:
    """Archard wear depth [m] of the cam surface each time a face passes, (F, N), at the
    cam point each face touches at each cam angle (0 where it is idle). ``a``: an
    Analysis, or a Local with its ``design`` and ``geo``."""
    design = a.design if design is None else design
    k = design.wear.coefficient_mm3_per_N_m * MM3_PER_N_M
    w = design.cam.width_mm * MM
    with np.errstate(invalid="ignore"):
        h = k * (np.maximum(a.FN, 0.0) / w) * sliding_ratio(a, geo)
    return np.where(a.in_contact & np.isfinite(h), h, 0.0)


def sliding_speed(a) -> np.ndarray:
    """v_s [m/s] per face (F, N) at the design speed; 0 where the face does not touch
    (a review: the idle face of a double follower had its geometry's sliding speed,
    up to 11.937 m/s in the paper's series and its report's maximum, where the contacts
    reach 11.9345)."""
    u = contact_travel(a, a.geo) * omega_rad_s(a.design)
    return np.where(a.in_contact, np.nan_to_num(sliding_ratio(a) * u), 0.0)


def pitting_life_cycles(a) -> float:
    """Estimated cycles to surface fatigue at the largest contact stress.

    inf where the stress stays within the allowable (the endurance region: the life
    curve is not extrapolated beyond N_ref) and for a knife edge (no Hertz stress)."""
    s = a.stress[np.isfinite(a.stress)]
    s_max = peak(a, "stress_max", float(s.max()) if s.size else 0.0) or 0.0  # (samples and between)
    allow = allowable_contact_stress_MPa(a.design) * MPA
    if s_max <= allow:
        return math.inf
    wm = a.design.wear
    return float(wm.pitting_reference_cycles * (allow / s_max) ** wm.pitting_exponent)


def total_at_contacts(a) -> np.ndarray:
    """Per cam angle of ``a``'s grid, the cam's total wear depth per cycle [m] at the
    cam point a face touches there (every pass of every face over that point,
    ``_totals``), the larger where two touch; 0 where none does. Its maximum is
    ``along_profile``'s, so a curve of it reaches the reported peak."""
    if _rolls(a.geo):
        return np.zeros(a.theta.size)
    loc, origin, totals = _worn(a)
    per_angle = np.where(loc.in_contact, totals, 0.0).max(axis=0)
    out = np.zeros(a.theta.size)
    np.maximum.at(out, origin, per_angle)
    return out


def along_profile(a, bins: int = 720) -> tuple[np.ndarray, np.ndarray]:
    """Wear depth per cycle [m] at the cam's surface, by polar angle of the cam point in
    the cam frame: (polar angles [rad] of the bin centres, depth). A bin holds the
    largest total (``_totals``) at the contacts that land in it; 0 where none does."""
    edges = np.linspace(0.0, 2 * np.pi, bins + 1)
    if _rolls(a.geo):
        return 0.5 * (edges[1:] + edges[:-1]), np.zeros(bins)
    loc, _, h = _worn(a)
    on = loc.in_contact
    where = np.minimum(np.searchsorted(edges, _polar(loc), side="right") - 1, bins - 1)
    out = np.zeros(bins)
    np.maximum.at(out, where[on], h[on])
    return 0.5 * (edges[1:] + edges[:-1]), out


# Half the gap [rad of cam angle] between the two one-sided samples of a segment
# boundary or a station (_one_sided), and how far inside its own pass the end sample of a
# pass asks the other passes for their depth [rad of polar angle] (_totals): far above
# the one-sided pair's own spread, far below a grid step.
SIDE_EPS = 1e-10
INSIDE = 1e-7


def _worn(a):
    """(_one_sided's local, its index into a's grid, _totals there), computed once per
    analysis: the report, the app's wear plot and its band on the cam each ask."""
    kept = vars(a).get("_worn")
    if kept is None:
        loc, origin, theta = _one_sided(a)
        kept = vars(a)["_worn"] = (loc, origin, _totals(a, loc, theta))
    return kept


def _one_sided(a):
    """``a`` evaluated again (a Local) where each sample on a motion segment boundary or a
    station is replaced by two, SIDE_EPS either side: the load and the contact's travel
    can step there, and a sample exactly on the boundary holds one side's values, or a
    mix. Returns (local, index into a's grid of each of its samples, its angles)."""
    cuts = np.mod(np.concatenate([[g.start for g in a.segments], a.stations]), 2 * np.pi)
    on_cut = (np.abs(a.theta[:, None] - cuts[None, :]) < 1e-12).any(axis=1)
    origin = np.repeat(np.arange(a.theta.size), np.where(on_cut, 2, 1))
    theta = a.theta[origin].copy()
    first = np.flatnonzero(on_cut[origin] & (np.diff(origin, prepend=-1) > 0))
    theta[first] -= SIDE_EPS
    theta[first + 1] += SIDE_EPS
    return a.local(theta), origin, theta


def _polar(loc) -> np.ndarray:
    """(F, N) polar angle [rad, 0..2 pi) of the cam point each face touches (cam frame)."""
    return np.mod(np.arctan2(loc.point_body[..., 1], loc.point_body[..., 0]), 2 * np.pi)


def _totals(a, loc, theta) -> np.ndarray:
    """(F, N) the total wear depth per cycle [m] at the cam point each face of ``loc``
    (at cam angles ``theta``) touches: its own pass's depth plus every other pass's
    (``_passes``, of every face) there, each interpolated by polar angle along its own
    cam points only, never across a jump or a gap. At the first or last sample of its
    pass a sample asks the others INSIDE its pass (it is worn from that side only).
    Adding the faces at the same cam point matters near a jump, where the two faces'
    largest passes within a bin of the cam lie at different points: a review measured
    a double follower's peak 21 % high when they were added per bin."""
    h, phi = depth_per_pass(loc, a.design, a.geo), _polar(loc)
    passes = _passes(loc, a.geo, theta, phi)
    ask = phi.copy()  # where each sample asks the other passes
    for f, idx, x, closed in passes:
        if idx.size > 1 and not closed:
            ask[f, idx[0]] += INSIDE * np.sign(x[-1] - x[0])
            ask[f, idx[-1]] -= INSIDE * np.sign(x[-1] - x[0])
    out = np.where(loc.in_contact, h, 0.0)
    for f, idx, x, closed in passes:
        own = np.zeros(h.shape, bool)
        own[f, idx] = True
        xs, hs = (x, h[f, idx]) if x[-1] >= x[0] else (x[::-1], h[f, idx][::-1])
        lo, hi = xs[0], xs[-1]
        for m in range(int(np.floor(lo / (2 * np.pi))) - 1, int(np.ceil(hi / (2 * np.pi))) + 1):
            q = ask + 2 * np.pi * m
            # a face always in touch passes each point once: its pass is half-open
            hit = loc.in_contact & ~own & (q >= lo) & ((q < hi) if closed else (q <= hi))
            out[hit] += np.interp(q[hit], xs, hs)
    return out


def _passes(loc, geo, theta, phi: np.ndarray) -> list:
    """Each face's passes over the cam: (face, sample indices in order, their unwrapped
    polar angles [rad], closed). A pass is a run of cyclically consecutive samples where
    the face touches and its contact point moves one way along the cam. It ends where
    the face leaves, where the contact turns back (that sample ends one pass and starts
    the next), and where it jumps: moves farther than its travel along the cam allows
    (1.5x the larger of the two samples' ds/dtheta over the step, plus 1 nm). closed:
    one pass all the way round, its last sample joined to its first."""
    n = theta.size
    nxt = np.roll(np.arange(n), -1)
    step = np.diff(theta, append=theta[0] + 2 * np.pi)  # sample i -> i + 1 [rad]
    travel = np.nan_to_num(contact_travel(loc, geo))
    runs = []
    for f in range(phi.shape[0]):
        on = loc.in_contact[f]
        gap = np.linalg.norm(loc.point_body[f, nxt] - loc.point_body[f], axis=-1)
        reach = 1.5 * np.maximum(travel[f], travel[f, nxt]) * step + 1e-9
        linked = on & on[nxt] & (gap <= reach)  # the step i -> i + 1 stays in one pass
        way = np.sign(np.angle(np.exp(1j * (phi[f, nxt] - phi[f]))))
        goes_on = linked & linked[nxt] & (way * way[nxt] >= 0)  # step i continues into i+1
        if goes_on.all():  # the last sample joined to the first, 2 pi on
            idx = np.append(np.arange(n), 0)
            runs.append((f, idx, np.unwrap(phi[f, idx]), True))
            continue
        starts = np.flatnonzero(linked & ~np.roll(goes_on, 1))
        ends = np.flatnonzero(linked & ~goes_on)
        for s0 in starts:  # each pass: steps s0 .. e (cyclic), samples s0 .. e + 1
            e = ends[np.searchsorted(ends, s0) % ends.size]
            idx = np.arange(s0, s0 + (e - s0) % n + 2) % n
            runs.append((f, idx, np.unwrap(phi[f, idx]), False))
        lone = on & ~linked & ~np.roll(linked, 1)  # a touch at one sample only
        runs += [(f, np.array([i]), phi[f, [i]], False) for i in np.flatnonzero(lone)]
    return runs
