"""Design limits: each broken limit becomes a Violation naming its equation, where it
fails (cam-angle ranges in degrees) and by how much.

Limits checked (on the contact points actually in use at each cam angle):

* ``curvature_convex``  Eq. 22, rho > 0: the cam must be convex.
* ``curvature_face``    Eq. 22, rho < |r_f| (concave faces): otherwise the face
  touches at several points or not at the synthesized one.
* ``roller_undercut``   rollers: rho > r_c, the conservative no-undercut rule
  (equivalently a pitch-curve radius above 2 r_c).
* ``pressure_angle``    Eqs. 5/13: |phi| <= the user's maximum (default 30 deg).
* ``high_dwell_arc``    Eq. 28, beta_h >= 4 psi_h (double followers).
* ``low_dwell_arc``     Eq. 27, beta_l >= 0 (already enforced by the model).
* ``jump``              Eqs. 29-41: contact force F_N <= 0 means the spring cannot
  keep the follower on the cam.
* ``guide_jam``         Eqs. 33-41: no guide-contact mode of Fig. 6 balances the
  follower with friction (self-locking).
* ``profile_crossing``  Eq. 22: the finished profile is not star-shaped about the
  axis (it crosses itself), which a convex cam never does; caught even when the
  sampled curvature misses it between grid angles.
* ``geometric_check``   the independent check (camcore.verify) finds the profile
  does not produce S(theta).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .motion import FALL, RISE

MM_PER_M = 1e3
RAD2DEG = 180.0 / math.pi
LIFT_TOLERANCE_M = 1e-8  # 1e-5 mm: far above round-off, far below any real defect


@dataclass(frozen=True)
class Violation:
    code: str
    equation: str
    message: str
    ranges_deg: tuple[tuple[float, float], ...] = ()
    amount: float = 0.0  # by how much the limit is exceeded, in the unit of the message

    def as_dict(self) -> dict:
        return {
            "code": self.code,
            "equation": self.equation,
            "message": self.message,
            "ranges_deg": [list(r) for r in self.ranges_deg],
            "amount": self.amount,
        }


def runs_deg(theta: np.ndarray, mask: np.ndarray) -> tuple[tuple[float, float], ...]:
    """Contiguous runs of ``mask`` over the grid, as (start, end) cam angles in degrees."""
    if not mask.any():
        return ()
    m = mask.astype(np.int8)
    edges = np.flatnonzero(np.diff(np.concatenate([[0], m, [0]])))
    return tuple(
        (round(float(theta[a] * RAD2DEG), 3), round(float(theta[b - 1] * RAD2DEG), 3))
        for a, b in zip(edges[::2], edges[1::2], strict=True)
    )


def _where(a, mask) -> str:
    r = runs_deg(a.theta, mask)
    shown = ", ".join(f"{s:g}-{e:g}" for s, e in r[:4])
    more = f" (+{len(r) - 4} more)" if len(r) > 4 else ""
    return f"theta = {shown} deg{more}"


def run_all(a, lift_error: float | None) -> list[Violation]:
    """Every violation of ``a`` (a camcore.analysis.Analysis)."""
    out: list[Violation] = []
    design = a.design
    on_curve = a.in_contact & ((a.part == RISE) | (a.part == FALL))
    rho_mm = a.rho * MM_PER_M

    bad = on_curve & (a.rho <= 0)
    if bad.any():
        worst = float(np.min(rho_mm[bad]))
        out.append(Violation(
            "curvature_convex", "Eq. 22",
            f"cam not convex (rho <= 0; min rho = {worst:.3g} mm) at {_where(a, bad.any(0))}",
            runs_deg(a.theta, bad.any(0)), -worst,
        ))
    if design.follower.kind.is_roller:
        rc = design.follower.roller_radius_mm
        bad = on_curve & (a.rho > 0) & (rho_mm < rc)
        if bad.any():
            worst = float(np.min(rho_mm[bad]))
            out.append(Violation(
                "roller_undercut", "Eq. 21",
                f"rho = {worst:.3g} mm is below the roller radius r_c = {rc:g} mm "
                f"(short by {rc - worst:.3g} mm) at {_where(a, bad.any(0))}",
                runs_deg(a.theta, bad.any(0)), rc - worst,
            ))
    else:
        rf = -design.follower.face_radius_mm
        bad = on_curve & ((rho_mm >= rf) | ~np.isfinite(a.rho))
        if bad.any():
            worst = float(np.max(np.where(np.isfinite(rho_mm[bad]), rho_mm[bad], np.inf)))
            out.append(Violation(
                "curvature_face", "Eq. 22",
                f"rho reaches {worst:.4g} mm, above |r_f| = {rf:g} mm "
                f"(by {worst - rf:.3g} mm) at {_where(a, bad.any(0))}",
                runs_deg(a.theta, bad.any(0)), worst - rf,
            ))

    limit = design.limits.max_pressure_angle_deg
    phi = np.abs(a.pressure_angle) * RAD2DEG
    bad = on_curve & (phi > limit)
    if bad.any():
        worst = float(np.max(phi[bad]))
        out.append(Violation(
            "pressure_angle", "Eqs. 5, 13",
            f"pressure angle {worst:.2f} deg exceeds the limit {limit:g} deg "
            f"by {worst - limit:.2f} deg at {_where(a, bad.any(0))}",
            runs_deg(a.theta, bad.any(0)), worst - limit,
        ))

    if design.follower.kind.is_double:
        need = 4 * a.geo.psi_h * RAD2DEG
        have = design.motion.high_dwell_deg
        if have < need - 1e-9:
            out.append(Violation(
                "high_dwell_arc", "Eq. 28",
                f"high dwell beta_h = {have:g} deg is below 4 psi_h = {need:.3f} deg "
                f"(short by {need - have:.3f} deg): both faces cannot rest on the dwell arc",
                (), need - have,
            ))
    if design.motion.low_dwell_deg < 0:
        out.append(Violation("low_dwell_arc", "Eq. 27", "beta_l < 0", (),
                             -design.motion.low_dwell_deg))

    touching = a.in_contact.any(0)
    bad = touching & (a.guide.FN <= 0)
    if bad.any():
        worst = float(np.min(a.guide.FN[bad]))
        out.append(Violation(
            "jump", "Eqs. 29-41",
            f"follower jump: contact force F_N = {worst:.3g} N <= 0 at {_where(a, bad)} "
            f"(raise the spring rate or preload, or lower the speed)",
            runs_deg(a.theta, bad), -worst,
        ))
    lost = ~touching
    if lost.any():
        out.append(Violation(
            "contact_lost", "Eq. 28",
            f"no face rests on the dwell arc at {_where(a, lost)}",
            runs_deg(a.theta, lost), float(lost.sum()),
        ))
    bad = touching & (a.guide.mode < 0)
    if bad.any():
        out.append(Violation(
            "guide_jam", "Eqs. 33-41",
            f"no guide-contact mode of Fig. 6 balances the follower with friction "
            f"mu = {design.dynamics.guide_friction:g} (self-locking) at {_where(a, bad)}",
            runs_deg(a.theta, bad), float(bad.sum()),
        ))
    if not a.profile.is_star_shaped():
        out.append(Violation(
            "profile_crossing", "Eq. 22",
            "the synthesized profile crosses itself (it is not star-shaped about the cam "
            "axis); no cam can be made from it",
            (), 1.0,
        ))
    if lift_error is not None and not lift_error <= LIFT_TOLERANCE_M:
        out.append(Violation(
            "geometric_check", "Eqs. 1-20",
            f"rotating the finished cam gives a follower lift that differs from S(theta) "
            f"by up to {lift_error * MM_PER_M:.4g} mm",
            (), lift_error * MM_PER_M,
        ))
    return out
