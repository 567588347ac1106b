"""Hertz line-contact stress between cam and follower (Eq. 42).

    sigma = sqrt( F_N (1/r + 1/rho) / (pi w [(1 - nu1^2)/E1 + (1 - nu2^2)/E2]) )

with the follower's signed radius r (roller r_c > 0; concave face r_f < 0, so a
concave face on a convex cam gives 1/rho - 1/|r_f|, a far smaller sum than a
roller's 1/rho + 1/r_c) and the cam's radius of curvature rho at the contact
(Eq. 21). It is the maximum (centre-line) pressure of a Hertzian line contact of
length w, e.g. Shigley's Mechanical Engineering Design, Sec. 3-19. Its contact strip
has the half-width b = sqrt(4 F_N C / (pi w sum)) = 2 F_N / (pi w sigma), with C the
compliance and sum = 1/r + 1/rho.

Where the formula stops being valid. Hertz treats each body as a half-space, which
holds while the strip is narrow beside both radii: b <= HERTZ_VALID_RATIO min(rho, |r|)
(Johnson, *Contact Mechanics*, Sec. 4.1, "a << R"). A concave face on a cam of nearly
its own radius (rho -> |r_f|) sends the curvature sum to zero and b to infinity: the
formula then promises a wide, gentle contact that the real, conforming bodies do not
give, so its stress is not conservative. There the stress used (checked, reported,
plotted) is the pressure 2 F_N / (pi w b_lim) of a strip no wider than the limit
b_lim = HERTZ_VALID_RATIO min(rho, |r|), which is higher than the Hertz value; the
report lists the angles where this applies.
"""

from __future__ import annotations

import numpy as np

from .model import MM, Design


def compliance(design: Design) -> float:
    """(1 - nu1^2)/E1 + (1 - nu2^2)/E2  [1/Pa]."""
    m = design.material
    return (1 - m.cam_nu**2) / (m.cam_E_GPa * 1e9) + (1 - m.follower_nu**2) / (
        m.follower_E_GPa * 1e9
    )


def hertz_line_stress(FN, r, rho, width, compliance_per_Pa):
    """Maximum Hertz pressure [Pa] of Eq. 42 (SI in, SI out).

    Where there is no compressive contact (F_N <= 0) or the curvature sum is not
    positive (a concave face no more curved than the cam, which Eq. 22 forbids) the
    Hertz solution does not exist and 0 is returned; the checks report those cases.
    """
    FN = np.asarray(FN, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        curv = 1.0 / r + 1.0 / np.asarray(rho, dtype=float)
        load = np.where((FN > 0) & (curv > 0), FN * curv, 0.0)
    return np.sqrt(load / (np.pi * width * compliance_per_Pa))


HERTZ_VALID_RATIO = 0.1  # largest half-width b / min(rho, |r|) taken as a half-space


def half_width(FN, stress, width) -> np.ndarray:
    """Half-width b [m] of the contact strip of a Hertz line contact: 2 F / (pi w sigma)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(stress > 0, 2.0 * np.asarray(FN) / (np.pi * width * stress), 0.0)


def half_width_limit(r: float, rho) -> np.ndarray:
    """b_lim [m]: the widest strip for which Hertz's half-space assumption holds."""
    return HERTZ_VALID_RATIO * np.minimum(np.abs(np.asarray(rho, dtype=float)), abs(r))


def conservative_stress(FN, stress, r: float, rho, width):
    """(stress [Pa], beyond) where ``beyond`` marks the contacts whose Hertz strip is
    wider than half_width_limit; there the stress is 2 F / (pi w b_lim) instead."""
    b_lim = half_width_limit(r, rho)
    beyond = half_width(FN, stress, width) > b_lim
    with np.errstate(divide="ignore", invalid="ignore"):
        capped = 2.0 * np.asarray(FN) / (np.pi * width * b_lim)
    return np.where(beyond, capped, stress), beyond


def contact_stress(design: Design, FN, rho) -> np.ndarray:
    """Eq. 42 for this design's follower radius, width and materials [Pa].

    A flat face (r = inf) is a cylinder of radius rho on a plane (1/r = 0). A knife edge
    (r = 0) touches along a line of zero radius: the Hertz stress is not defined
    (infinite in theory), so it is NaN and no stress limit is checked for it. Where the
    line-contact formula is beyond its validity, the conservative value (module doc)."""
    r = design.follower.radius_mm * MM
    if r == 0.0:
        return np.full(np.shape(FN), np.nan)
    w = design.cam.width_mm * MM
    plain = hertz_line_stress(FN, r, rho, w, compliance(design))
    return conservative_stress(FN, plain, r, rho, w)[0]


def hertz_validity(design: Design, FN, rho) -> tuple[np.ndarray, np.ndarray]:
    """(b, beyond): the Hertz half-width [m] of each contact and where it passes the
    half-space limit (there contact_stress gives the conservative value). Knife edge:
    b undefined (NaN, as its stress: no Hertz contact at all; a review read "0.0000 mm"
    beside no stress), never beyond."""
    r = design.follower.radius_mm * MM
    if r == 0.0:
        return np.full(np.shape(FN), np.nan), np.zeros(np.shape(FN), bool)
    w = design.cam.width_mm * MM
    b = half_width(FN, hertz_line_stress(FN, r, rho, w, compliance(design)), w)
    return b, b > half_width_limit(r, rho)
