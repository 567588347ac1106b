"""The floor: a minimal numpy evaluation of the paper example's closed forms.

What one analysis cannot do with less work: S, V, A of the cycloidal rise and fall on
the grid, and for each face the pressure angle (Eq. 13), the pitch curvature and the
cam's radius of curvature (Eq. 21 as a parallel curve), the contact point in the world
(Eqs. 10, 18) and on the cam (Eq. 11). No forces, no checks, no profile assembly: a
lower bound to compare camcore.analysis.analyze against, measured in the same run
(issue 12: the analysis should cost at most 3x this). ``tests/test_bench_floor.py``
checks that the floor computes the same numbers as camcore, so it stays honest.
"""

from __future__ import annotations

import math

import numpy as np

from camcore import profile
from camcore.model import Design


def constants(design: Design) -> dict:
    """Scalars of the design the per-angle work needs (computed once, not timed)."""
    m, geo = design.motion, profile.geometry(design)
    return {
        "h": m.lift_mm * 1e-3,
        "b1": math.radians(m.rise_deg),
        "t2": math.radians(m.rise_deg + m.high_dwell_deg),
        "b3": math.radians(m.fall_deg),
        "y0": geo.y0,
        "sigma": geo.sigma,
        "r": geo.r,
        "faces": [f.x_c for f in geo.faces],
    }


def floor(theta: np.ndarray, c: dict) -> dict:
    """The closed forms on the angles ``theta`` [rad] (cycloidal rise and fall)."""
    h, b1, t2, b3 = c["h"], c["b1"], c["t2"], c["b3"]
    two_pi = 2 * math.pi
    x1 = np.clip(theta / b1, 0.0, 1.0)
    x3 = np.clip((theta - t2) / b3, 0.0, 1.0)
    rise, fall = theta < b1, (theta >= t2) & (theta < t2 + b3)
    S = h * (x1 - np.sin(two_pi * x1) / two_pi) - h * (x3 - np.sin(two_pi * x3) / two_pi)
    V = np.where(rise, h / b1 * (1 - np.cos(two_pi * x1)), 0.0) - np.where(
        fall, h / b3 * (1 - np.cos(two_pi * x3)), 0.0
    )
    A = np.where(rise, two_pi * h / b1**2 * np.sin(two_pi * x1), 0.0) - np.where(
        fall, two_pi * h / b3**2 * np.sin(two_pi * x3), 0.0
    )
    Y = c["y0"] + S
    cs, sn = np.cos(theta), np.sin(theta)
    out = {"S": S, "V": V, "A": A, "phi": [], "rho": [], "body": []}
    for x_c in c["faces"]:
        u = x_c + V
        hyp = np.hypot(u, Y)
        out["phi"].append(np.arctan(u / np.abs(Y)))
        kappa = (Y * Y + u * (u + V) - A * Y) / hyp**3
        out["rho"].append(c["sigma"] / kappa - c["r"])
        nx, ny = c["sigma"] * u / hyp, c["sigma"] * Y / hyp  # normal through I23 and C
        px, py = x_c - c["r"] * nx, Y - c["r"] * ny  # contact point A = C - r n
        out["body"].append((cs * px - sn * py, sn * px + cs * py))  # Eq. 11
    return out
