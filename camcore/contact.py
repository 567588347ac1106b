"""Hertz line-contact stress between cam and follower (Eq. 42).

    sigma = sqrt( F_N (1/r + 1/rho) / (pi w [(1 - nu1^2)/E1 + (1 - nu2^2)/E2]) )

with the follower's signed radius r (roller r_c > 0; concave face r_f < 0, so a
concave face on a convex cam gives 1/rho - 1/|r_f|, a far smaller sum than a
roller's 1/rho + 1/r_c) and the cam's radius of curvature rho at the contact
(Eq. 21). It is the maximum (centre-line) pressure of a Hertzian line contact of
length w, e.g. Shigley's Mechanical Engineering Design, Sec. 3-19.
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


def contact_stress(design: Design, FN, rho) -> np.ndarray:
    """Eq. 42 for this design's follower radius, width and materials [Pa].

    A flat face (r = inf) is a cylinder of radius rho on a plane (1/r = 0). A knife edge
    (r = 0) touches along a line of zero radius: the Hertz stress is not defined
    (infinite in theory), so it is NaN and no stress limit is checked for it."""
    r = design.follower.radius_mm * MM
    if r == 0.0:
        return np.full(np.shape(FN), np.nan)
    return hertz_line_stress(
        FN, r, rho, design.cam.width_mm * MM, compliance(design)
    )
