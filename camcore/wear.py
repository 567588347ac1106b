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


def sliding_ratio(a) -> np.ndarray:
    """v_s / u per face (F, N): sliding speed over the contact's speed along the cam
    (dimensionless, speed-independent); 0 for rollers, NaN where the contact does not
    move along the cam (u = 0)."""
    if a.geo.r > 0 and not a.geo.flat:  # rollers roll
        return np.zeros(a.FN.shape)
    vs = np.abs(tangential_slip(a.point_world, a.normal, a.prog.V))
    u = contact_travel(a, a.geo)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(u > 0, vs / u, np.nan)


def depth_per_pass(a) -> np.ndarray:
    """Archard wear depth [m] of the cam surface each time a face passes, (F, N), at the
    cam point each face touches at each cam angle (0 where it is idle)."""
    k = a.design.wear.coefficient_mm3_per_N_m * MM3_PER_N_M
    w = a.design.cam.width_mm * MM
    with np.errstate(invalid="ignore"):
        h = k * (np.maximum(a.FN, 0.0) / w) * sliding_ratio(a)
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


def total_at_contacts(a, bins: int = 720) -> np.ndarray:
    """Per cam angle, the cam's total wear depth per cycle [m] (``along_profile``: all
    faces' passes) at the cam point a face touches there, the larger where two touch;
    0 where none does. Its maximum over the angles is ``along_profile``'s maximum (every
    worn bin is one that a face touches), so a curve of it reaches the reported peak."""
    _, total = along_profile(a, bins)
    return np.where(a.in_contact, total[_bins(a, bins)], 0.0).max(axis=0)


def _bins(a, bins: int) -> np.ndarray:
    """(F, N) the bin of the cam point each face touches, by its polar angle."""
    phi = np.mod(np.arctan2(a.point_body[..., 1], a.point_body[..., 0]), 2 * np.pi)
    edges = np.linspace(0.0, 2 * np.pi, bins + 1)
    return np.minimum(np.searchsorted(edges, phi, side="right") - 1, bins - 1)


def along_profile(a, bins: int = 720) -> tuple[np.ndarray, np.ndarray]:
    """Wear depth per cycle [m] at the cam's surface, by polar angle of the cam point in
    the cam frame: (polar angles [rad] of the bin centres, depth). Each face's passes are
    added where they land, so a dwell arc that both faces of a double follower slide on
    counts both. The depth of a bin is the largest of the passes that land in it."""
    h, where = depth_per_pass(a), _bins(a, bins)
    edges = np.linspace(0.0, 2 * np.pi, bins + 1)
    out = np.zeros(bins)
    for f in range(h.shape[0]):
        on = a.in_contact[f]
        per = np.zeros(bins)
        np.maximum.at(per, where[f][on], h[f][on])
        out += per
    return 0.5 * (edges[1:] + edges[:-1]), out
