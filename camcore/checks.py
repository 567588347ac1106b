"""Design limits: each broken limit becomes a Violation naming its source (the paper's
equation, or the rule it comes from), where it fails (cam-angle ranges in degrees) and
by how much.

Limits are checked on the contact points actually in use at each cam angle, and on
the rise and fall curves also between the grid samples (camcore.extremes), so a
verdict holds for the real cam, not only at the analysed angles:

* ``curvature_convex``  concave faces, Eq. 22, rho > 0: the cam must be convex; where
  the pitch-curve radius 1/kappa_p reaches |r_f| the profile folds back (rho < 0).
* ``curvature_face``    concave faces, Eq. 22, rho < |r_f|: a cam flatter than the
  face touches it at two points or at the wrong one. A flat face needs a convex cam
  too: ``curvature_convex`` when rho = r_b + S + S'' <= 0 (a cusp, the classic rule);
  a knife edge has no curvature rule (it follows concave flanks).
* ``roller_undercut``   rollers: the pitch curve's radius must not lie in (0, r_c]
  (the parallel curve at r_c folds back there; not in the paper, the classic undercut
  rule, e.g. Norton, Cam Design and Manufacturing Handbook, ch. 7). A roller runs
  happily on a concave flank (rho < -r_c).
* ``pressure_angle``    Eqs. 5/13 against the user's maximum (default 30 deg).
* ``contact_stress``    Eq. 42: the maximum Hertz stress times the safety factor
  (limits.contact_stress_safety_factor) against the allowable stress (the user's, or
  the default of material.grade; see camcore.model.ALLOWABLE_CONTACT_STRESS_MPa).
* ``high_dwell_arc``    Eq. 28, beta_h >= 4 psi_h (double followers).
* ``low_dwell_arc``     Eq. 27, beta_l >= 0: enforced by the model (the angles of a
  program sum to 360 deg), so never reported.
* ``velocity_jump``, ``acceleration_jump``  the fundamental law of cam design: V and A
  continuous where segments meet (an infinite acceleration or jerk otherwise); the
  second can be waived (limits.require_continuous_acceleration).
* ``jump``              Eqs. 29-41: contact force F_N < 0 means the spring cannot
  keep the follower on the cam.
* ``jump_speed``        Eq. 29 (camcore.machine): with limits.min_jump_speed_ratio
  set, the speed at which the rigid follower would leave the cam must be at least that
  many times the cam speed (a designer's margin for a machine that runs faster or
  overshoots; not in the paper; the elastic train is judged at the speed itself).
* ``guide_jam``         Eqs. 33-41: no guide-contact mode of Fig. 6 balances the
  follower with friction (self-locking).
* ``guide_overhang``    Fig. 5: with the overhang shrinking as the follower rises (l1 =
  l1_0 - S), l1 must not go below 0: at l1 < 0 the face is inside its guide, and
  Eqs. 35, 41's arms are not a follower's (not in the paper, whose l1_0 = 30 mm
  exceeds its h = 15 mm).
* ``profile_crossing``  the finished profile is not star-shaped about the axis (it
  crosses itself), which a convex cam never does.
* ``export_tolerance``  the profile cannot be sampled so that every chord stays within
  limits.export_tolerance_mm of the exact cam (it has cusps or folds).
* ``hub_wall``          with a shaft bore: the thinnest wall between the bore (and its
  keyway) and the profile must reach limits.min_hub_wall_mm (a maker's limit).
* ``outer_diameter``    with limits.max_outer_diameter_mm set, the cam's outer
  diameter (outer_diameter_mm: the exact cam's, from its profile) must stay within it
  (a designer's envelope, a maker's stock).
* ``geometric_check``   the independent check (camcore.verify) finds the profile
  does not produce S(theta) within the export tolerance over cos(pressure angle).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import extremes, forces
from .model import FollowerKind
from .units import MM, to_deg, to_mm

# every violation code, in the order run_all reports them (a sweep's map gives each
# its own colour, the same in every sweep)
CODES = (
    "curvature_convex",
    "curvature_face",
    "roller_undercut",
    "pressure_angle",
    "contact_stress",
    "high_dwell_arc",
    "rollers_overlap",
    "velocity_jump",
    "acceleration_jump",
    "jump",
    "guide_jam",
    "guide_overhang",
    "contact_lost",
    "dynamic_jump",
    "jump_speed",
    "profile_crossing",
    "export_tolerance",
    "hub_wall",
    "outer_diameter",
    "geometric_check",
)

LIFT_TOLERANCE_M = 1e-8  # 1e-5 mm: far above round-off, far below any real defect
ROUND_OFF_MM = 1e-9  # a size this far past its limit meets it (190.00000000000003 mm)
ROUND_OFF = 1e-9  # relative: a figure this close past its limit meets it (a review: the
# double rollers' sin phi = e / (r_b + r_c) = 1/2 gave phi = 30.000000000000004 deg, and
# "exceeds the limit 30 deg by 0.00 deg" refused a design exactly at it)


def most(limit: float) -> float:
    """The largest figure that meets "at most ``limit``": the limit, with the closed
    forms' round-off (ROUND_OFF)."""
    return limit + ROUND_OFF * abs(limit)


def least(limit: float) -> float:
    """The smallest figure that meets "at least ``limit``" (as ``most``)."""
    return limit - ROUND_OFF * abs(limit)


def _by(excess: float) -> str:
    """How far past a limit, in two decimals or, below them, two significant figures
    (never "by 0.00")."""
    return f"{excess:.2f}" if excess >= 0.005 else f"{excess:.2g}"


def lift_tolerance(a) -> float:
    """What the geometric check may find on a correct cam [m]: the profile's chords lie
    up to the export tolerance inside the exact cam (camcore.sampling), which lowers the
    follower by at most that over cos(pressure angle); plus LIFT_TOLERANCE_M for
    round-off. The *requested* tolerance, not the measured chord error: a profile that
    cannot be sampled to it is reported (export_tolerance), never excused."""
    w = a.worst.get("pressure_angle_max")
    phi = min(w.value if w else 0.0, math.radians(89.0))
    return LIFT_TOLERANCE_M + a.design.limits.export_tolerance_mm * MM / math.cos(phi)


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


# the limits whose breach gives the profile a cusp or a fold (its rho reaches 0): a
# sharp corner on the part (export.warning) and an unbounded contact stress
# (report.cusp_note)
CUSPED = frozenset({"roller_undercut", "curvature_convex"})


def runs_deg(
    theta: np.ndarray, mask: np.ndarray, extra: tuple[tuple[float, float], ...] = ()
) -> tuple[tuple[float, float], ...]:
    """Contiguous runs of ``mask`` over the grid, with the brackets ``extra`` [rad] of
    breaks found between the samples, merged, as (start, end) cam angles in degrees.
    A run through theta = 0 on the design's whole-turn grid is its two parts, the last
    ending at 360 (where_text says it as one)."""
    m = mask.astype(np.int8)
    edges = np.flatnonzero(np.diff(np.concatenate([[0], m, [0]])))
    spans = [
        (float(theta[a]), float(theta[b - 1])) for a, b in zip(edges[::2], edges[1::2], strict=True)
    ]
    two_pi = 2 * np.pi
    if spans and m[0] and m[-1] and spans[0][0] == 0.0 and extremes.whole_turn(theta):
        spans[-1] = (spans[-1][0], two_pi)  # (the run goes on at the first sample)
    turn = []  # a bracket across theta = 0 (extremes.brackets) as its two parts in [0, 2 pi]
    for lo, hi in extra:
        if lo < 0.0:
            turn += [(lo + two_pi, two_pi), (0.0, hi)]
        elif hi > two_pi:
            turn += [(lo, two_pi), (0.0, hi - two_pi)]
        else:
            turn.append((lo, hi))
    merged: list[list[float]] = []
    for lo, hi in sorted(spans + turn):
        if merged and lo <= merged[-1][1] + 1e-12:
            merged[-1][1] = max(merged[-1][1], hi)
        else:
            merged.append([lo, hi])
    return tuple((round(float(to_deg(lo)), 3), round(float(to_deg(hi)), 3)) for lo, hi in merged)


def merged_deg(ranges) -> tuple[tuple[float, float], ...]:
    """Ranges [deg] of several violations as one sorted list, overlapping ones merged
    (where_text reads a list of disjoint runs, as runs_deg makes)."""
    out: list[list[float]] = []
    for lo, hi in sorted(tuple(r) for r in ranges):
        if out and lo <= out[-1][1]:
            out[-1][1] = max(out[-1][1], hi)
        else:
            out.append([lo, hi])
    return tuple((lo, hi) for lo, hi in out)


def where_text(ranges: tuple[tuple[float, float], ...]) -> str:
    """Cam-angle ranges [deg] in words: "theta = 10-20, 35 deg (+2 more)"; a range
    through theta = 0 (its two parts, one from 0, one to 360: runs_deg) as one,
    "theta = 350-10 (through 0) deg"."""
    if len(ranges) > 1 and ranges[0][0] == 0 and ranges[-1][1] == 360:
        ranges = ((ranges[-1][0], ranges[0][1]), *ranges[1:-1])

    def span(s: float, e: float) -> str:
        if f"{s:g}" == f"{e:g}":
            return f"{s:g}"
        return f"{s:g}-{e:g}" + (" (through 0)" if s > e else "")

    shown = ", ".join(span(s, e) for s, e in ranges[:4])
    more = f" (+{len(ranges) - 4} more)" if len(ranges) > 4 else ""
    return f"theta = {shown} deg{more}"


def rho_reference_mm(design) -> tuple[str, float]:
    """(label, value [mm]) of the radius that bounds the cam's radius of curvature rho
    for the design's follower, as the curvature rules below use it: |r_f| for a
    concave face (0 < rho < |r_f|, Eq. 22), 0 for a flat face (rho > 0), a roller and a
    knife edge (no rule: drawn at 0).

    A roller's rule is on the pitch radius rho_p = rho + r_c: undercut where it lies in
    (0, r_c], that is -r_c < rho <= 0 on the cam; a concave flank has rho < -r_c, which
    is sound. So the cam's rho meets its limit at 0, not at r_c (a designer's review:
    the curve's line at r_c had said a sound 1.9 mm against a 55 mm roller broke it)."""
    f = design.follower
    if f.kind.is_concave:
        return "|r_f|", -f.face_radius_mm
    return "0", 0.0


def _curvature_rules(a) -> list[Violation]:
    """Eq. 22 for concave faces, the undercut rule for rollers, in terms of the
    pitch-curve curvature kappa_p (rho = sigma / kappa_p - r, camcore.profile)."""
    on, k = a.on_curve, a.kappa_pitch
    out: list[Violation] = []
    if a.geo.r == 0.0:  # knife edge: the pitch curve is the profile, concave flanks are fine
        return out
    if a.geo.flat:  # flat face: rho = r_b + S + S'' > 0, kappa_p its reciprocal
        worst = a.worst.get("pitch_radius_min")
        cands = worst.others if worst else ()
        bad = on & (k <= 0)
        extra = tuple((lo, hi) for v, lo, hi in cands if v <= 0)
        if bad.any() or extra:
            rho = [float(np.min(a.rho[bad]))] if bad.any() else []
            rho += [v for v, _, _ in cands if v <= 0]
            ranges = runs_deg(a.theta, bad.any(0), extra)
            low = min(rho) if rho else 0.0
            out.append(
                Violation(
                    "curvature_convex",
                    "flat face: rho = r_b + S + S'' > 0",
                    f"cam not convex under the flat face: rho = r_b + S + S'' falls to "
                    f"{to_mm(low):.4g} mm (a cusp; raise r_b or soften the law) at "
                    f"{where_text(ranges)}",
                    ranges,
                    -to_mm(low),
                )
            )
        return out
    if a.geo.r > 0:  # rollers: the pitch radius 1/kappa_p must not lie in (0, r_c]
        rc = a.geo.r
        worst = a.worst.get("kappa_pitch_max")
        bad = on & (k >= 1.0 / rc)
        extra = worst.beyond(1.0 / rc, 1.0) if worst else ()
        if bad.any() or extra:
            kmax = max(float(k[bad].max()) if bad.any() else 0.0, worst.value if worst else 0.0)
            ranges = runs_deg(a.theta, bad.any(0), extra)
            short = to_mm(rc - 1.0 / kmax)
            out.append(
                Violation(
                    "roller_undercut",
                    "undercut: pitch radius > r_c",
                    f"the pitch curve's radius falls to {to_mm(1.0 / kmax):.4g} mm, inside "
                    f"(0, r_c = {to_mm(rc):g} mm] (by {short:.3g} mm): the profile undercuts "
                    f"(folds back) at {where_text(ranges)}",
                    ranges,
                    short,
                )
            )
        return out
    rf = -a.geo.r  # concave faces: 0 < rho < |r_f| (Eq. 22) <=> kappa_p > 1/|r_f|
    worst = a.worst.get("kappa_pitch_min")
    cands = worst.others if worst else ()
    fold = on & (k > 0) & (k <= 1.0 / rf)
    extra = tuple((lo, hi) for v, lo, hi in cands if 0 < v <= 1.0 / rf)
    if fold.any() or extra:
        rho = [float(np.min(a.rho[fold]))] if fold.any() else []
        rho += [rf - 1.0 / v for v, _, _ in cands if 0 < v <= 1.0 / rf]
        ranges = runs_deg(a.theta, fold.any(0), extra)
        out.append(
            Violation(
                "curvature_convex",
                "Eq. 22",
                f"cam not convex: the profile folds back (rho down to {to_mm(min(rho)):.4g} mm "
                f"<= 0; the pitch radius passes |r_f| = {to_mm(rf):g} mm) at {where_text(ranges)}",
                ranges,
                -to_mm(min(rho)),
            )
        )
    flat = on & (k <= 0)
    extra = tuple((lo, hi) for v, lo, hi in cands if v <= 0)
    if flat.any() or extra:
        finite = a.rho[flat & np.isfinite(a.rho)]
        worst_rho = float(finite.max()) if finite.size else math.inf
        ranges = runs_deg(a.theta, flat.any(0), extra)
        how = (
            f"its radius of curvature reaches {to_mm(worst_rho):.4g} mm"
            if math.isfinite(worst_rho)
            else "it is straight or concave"
        )
        out.append(
            Violation(
                "curvature_face",
                "Eq. 22",
                f"the cam is flatter than the concave face: {how}, where it must stay "
                f"below |r_f| = {to_mm(rf):g} mm (else the face bears on its edges, not on "
                f"one line of contact) at {where_text(ranges)}",
                ranges,
                to_mm(worst_rho - rf) if math.isfinite(worst_rho) else to_mm(rf),
            )
        )
    return out


def _pressure_angle(a) -> list[Violation]:
    limit = a.design.limits.max_pressure_angle_deg
    phi = to_deg(np.abs(a.pressure_angle))
    bad = a.on_curve & (phi > most(limit))
    worst = a.worst.get("pressure_angle_max")
    extra = worst.beyond(most(math.radians(limit)), 1.0) if worst else ()
    if not (bad.any() or extra):
        return []
    top = max(float(phi[bad].max()) if bad.any() else 0.0, to_deg(worst.value) if worst else 0)
    ranges = runs_deg(a.theta, np.asarray(bad.any(0)), extra)
    return [
        Violation(
            "pressure_angle",
            "Eqs. 5, 13",
            f"pressure angle {top:.2f} deg exceeds the limit {limit:g} deg "
            f"by {_by(top - limit)} deg at {where_text(ranges)}",
            ranges,
            top - limit,
        )
    ]


def _contact_stress(a) -> list[Violation]:
    from .model import allowable_contact_stress_MPa, contact_stress_limit_MPa

    if a.geo.r == 0.0:  # knife edge: no Hertz stress to check (camcore.contact)
        return []
    allow = allowable_contact_stress_MPa(a.design) * 1e6  # [Pa]
    sf = a.design.limits.contact_stress_safety_factor
    limit = contact_stress_limit_MPa(a.design) * 1e6  # the largest stress allowed [Pa]
    stress = np.where(a.in_contact, a.stress, 0.0)
    bad = stress > most(limit)
    worst = a.worst.get("stress_max")
    extra = worst.beyond(most(limit), 1.0) if worst else ()
    if not (bad.any() or extra):
        return []
    top = max(float(stress.max()), worst.value if worst else 0.0)
    ranges = runs_deg(a.theta, np.asarray(bad.any(0)), extra)
    rho = _near_cusp(a, bad, worst, top, allow)
    if rho is not None:  # (a review: "8335972.2 MPa" beside a headline of "unbounded")
        message = (
            f"Hertz stress without bound at {where_text(ranges)}: the cam's radius of "
            f"curvature falls to {rho * 1e3:.3g} mm there (Eq. 21: a near cusp), where "
            f"Eq. 42 grows without bound (at its largest found, with the safety factor {sf:g}: "
            f"more than {_times(top * sf / allow)} the allowable {allow / 1e6:g} MPa); "
            "fix the curvature first"
        )
    elif _jams(a) and top >= 10 * allow:  # (the same review: "2519398.3 MPa" at a jam)
        message = (
            f"Hertz stress without bound at {where_text(ranges)}: the guide jams "
            f"(self-locking, Eqs. 33-41), and toward the jam F_N grows without bound "
            f"(at its largest found, with the safety factor {sf:g}: more than "
            f"{_times(top * sf / allow)} the allowable {allow / 1e6:g} MPa); "
            "fix the guide first"
        )
    else:
        message = (
            f"Hertz stress {top / 1e6:.1f} MPa x safety factor {sf:g} = "
            f"{top * sf / 1e6:.1f} MPa exceeds the allowable {allow / 1e6:g} MPa by "
            f"{_by((top * sf - allow) / 1e6)} MPa at {where_text(ranges)}"
        )
    return [Violation("contact_stress", "Eq. 42", message, ranges, (top * sf - allow) / 1e6)]


def _times(ratio: float) -> str:
    """ "ten times" .. "a million times": the power of ten a ratio (>= 10) passes."""
    words = ("ten", "a hundred", "a thousand", "ten thousand", "a hundred thousand")
    if not math.isfinite(ratio):  # (rho = 0 at a sample: an infinite stress; a fuzzer's
        return "a million times"  # OverflowError had stopped report and sweep)
    p = int(math.floor(math.log10(ratio))) if ratio >= 10 else 1
    return f"{words[p - 1] if p <= len(words) else 'a million'} times"


def _jammed(a) -> np.ndarray:
    """(N,) the samples where a face touches and no guide mode balances (forces.jammed):
    the guide_jam check's."""
    return a.in_contact.any(0) & forces.jammed(a.guide)


def _jams(a) -> bool:
    """Whether the guide jams anywhere a face touches, on the grid or between its
    samples (the guide_jam check of _forces)."""
    return bool(_jammed(a).any() or a.worst.get("guide_jam"))


def _near_cusp(a, bad: np.ndarray, worst, top: float, allow: float) -> float | None:
    """The cam's smallest radius of curvature [m] where the stress is over its limit
    (``bad``: per face and sample; ``worst``: the refined stress_max, between the
    samples), if the stress is many times the allowable because that radius nears
    zero (a cusp: Eq. 42 grows without bound as rho -> 0): the number is then the
    formula's, not a stress the part could carry, and the curvature limit (Eqs. 21-22)
    is what to fix. None otherwise. (A review saw "890265.2 MPa", a peak between the
    samples where rho nears 0, beside a cusp the headline called unbounded: the
    samples' own rho there was 0.61 mm.)"""
    if top < 10 * allow:
        return None
    rho = [float(np.min(np.abs(a.rho[bad])))] if bad.any() else []
    if worst is not None and np.isfinite(worst.value):  # rho at the refined peak
        rho.append(abs(float(a.local(np.array([worst.theta])).rho[worst.face, 0])))
    least = min(rho, default=np.inf)
    return least if least < 0.01 * a.design.cam.base_radius_mm * 1e-3 else None


def _dwell_arcs(a) -> list[Violation]:
    """Eq. 28 for every dwell a double follower enters on its rise face and leaves on
    its fall face (a rise, then the dwell, then a fall; a rise straight into a fall is
    such a dwell of length 0): beta >= 4 psi at the dwell's own radius, so that both
    faces can rest on its arc (Eq. 24: the arc is beta - 2 psi). Dwells between a fall
    and a rise (Eqs. 26, 27) or between two motions the same way need nothing."""
    from dataclasses import replace

    from .motion import FALL, RISE, segments
    from .profile import dwell_psi, dwell_run

    out: list[Violation] = []
    if len(a.geo.faces) != 2:
        return out
    segs = segments(a.design)
    for i, g in enumerate(segs):
        after = segs[(i + 1) % len(segs)]
        if g.code == RISE and after.code == FALL:  # no dwell at all between them
            g, length = replace_dwell(g), 0.0
        elif g.is_motion:
            continue
        else:  # a run of dwells in a row is one dwell (profile.dwell_run)
            run = dwell_run(segs, i)
            if run.head != i or not (run.before.code == RISE and run.after.code == FALL):
                continue
            start = run.t0 % (2 * math.pi)
            g, length = replace(g, start=start, end=start + run.t1 - run.t0), run.t1 - run.t0
        need = to_deg(4 * dwell_psi(a.geo, g.S0))
        have = to_deg(length)
        if have < least(need):
            name = (
                "high dwell beta_h"
                if a.design.motion.classic
                else (f"dwell at {to_deg(g.start):.2f} deg")
            )
            out.append(
                Violation(
                    "high_dwell_arc",
                    "Eq. 28",
                    f"{name} = {have:g} deg is below 4 psi = {need:.3f} deg "
                    f"(short by {_by(need - have)} deg): both faces cannot rest on the dwell arc",
                    _on_circle_deg(to_deg(g.start), to_deg(g.end)),
                    need - have,
                )
            )
    return out


def rollers_apart(a) -> list[Violation]:
    """A double roller's two rollers, of radius r_c at X = -e and +e, must not touch:
    2 e > 2 r_c (not in the paper, whose e = 10 mm clears its r_c = 8 mm; a designer's
    review found overlapping rollers valid, and a sweep's Pareto front led with them).
    Needs only the design and its faces (e = 0: one roller, analysed as one face)."""
    f = a.design.follower
    if f.kind != FollowerKind.double_roller or len(a.geo.faces) != 2:
        return []
    gap = 2 * (f.offset_mm - f.roller_radius_mm)
    if gap > 0:
        return []
    return [
        Violation(
            "rollers_overlap",
            "double rollers",
            f"the two rollers (r_c = {f.roller_radius_mm:g} mm at X = +-e = +-{f.offset_mm:g} "
            f"mm) {'touch' if gap == 0 else f'overlap by {-gap:.4g} mm'}: e must exceed r_c, "
            "with room for their pins and the yoke",
            (),
            -gap,
        )
    ]


def lift_peak_mm(design, prog=None) -> float:
    """The program's largest S [mm], between the samples too: its lifts' sum h, or more
    where a law overshoots the segment's end (an adversarial review: a polynomial
    blend into a fall reached 23.373 mm of a 23 mm program, and the guide check read
    h). ``prog``: the program on the analysis grid, if at hand (else the design's grid
    is evaluated); only its largest samples are searched between."""
    from .motion import program, segments, theta_grid

    segs = segments(design)
    if prog is None:
        prog = program(design, theta_grid(design), segs)
    [(top, _)] = extremes.refine_maxes(
        lambda x: program(design, x, segs).S[None], prog.theta, [prog.S]
    )
    return max(design.motion.lift_mm, to_mm(top))


def face_in_guide(a, peak_mm: float | None = None) -> list[Violation]:
    """The overhang l1 = l1_0 - S at full lift must not go below 0 (module docstring;
    a physics review: l1_0 = 5 mm with h = 15 mm passed, its guide forces computed with
    l1 down to -10 mm). Decided on the program's largest S between the samples
    (lift_peak_mm, or ``peak_mm`` if the caller has it: the batched core's designs share
    one program); the ranges are the samples' where l1 < 0. Needs the design (and
    a.prog for the ranges, which the batched core leaves empty)."""
    dyn = a.design.dynamics
    if not dyn.overhang_shrinks:
        return []
    prog = getattr(a, "prog", None)
    if peak_mm is None and prog is not None:
        # S between two samples exceeds theirs by at most step^2 / 8 max |S''|: an
        # overhang beyond twice that needs no search (it costs 7 % of an analysis)
        step = float(np.diff(prog.theta).max())
        reach = float(prog.S.max() + step**2 / 4 * np.abs(prog.A).max())
        if dyn.overhang_mm >= to_mm(reach):
            return []
    h = lift_peak_mm(a.design, prog) if peak_mm is None else peak_mm
    if dyn.overhang_mm >= h - ROUND_OFF_MM:  # (l1 = 0: the face at the guide's end)
        return []
    ranges = (
        () if prog is None else runs_deg(a.theta, to_mm(prog.S) > dyn.overhang_mm + ROUND_OFF_MM)
    )
    return [
        Violation(
            "guide_overhang",
            "Fig. 5, Eqs. 35, 41",
            f"the follower's face enters its guide: the overhang l1 = l1_0 - S = "
            f"{dyn.overhang_mm:g} - {h:.4g} = {dyn.overhang_mm - h:.4g} mm at full lift, must "
            f"stay >= 0 (raise the overhang (dynamics.overhang_mm) to the lift or more)"
            + (f" at {where_text(ranges)}" if ranges else ""),
            ranges,
            h - dyn.overhang_mm,
        )
    ]


def _on_circle_deg(lo: float, hi: float) -> tuple[tuple[float, float], ...]:
    """The range [lo, hi] [deg] within [0, 360]: split in two where it passes 360."""
    if hi <= 360.0:
        return ((lo, hi),)
    return ((lo, 360.0), (0.0, hi - 360.0))


def replace_dwell(rise):
    """The empty dwell where a rise meets a fall directly (at the top of the rise)."""
    from dataclasses import replace

    from .motion import HIGH

    return replace(rise, code=HIGH, start=rise.end, S0=rise.S1, law=None, coeffs=None)


def _continuity(a) -> list[Violation]:
    """The fundamental law of cam design: S, V and A continuous over the whole cycle
    (a jump in V is an infinite acceleration, one in A an infinite jerk). A jump in A
    is allowed when limits.require_continuous_acceleration is off."""
    from .motion import continuity_jumps, segments

    out = []
    for at, what, jump in continuity_jumps(segments(a.design)):
        if what == "A" and not a.design.limits.require_continuous_acceleration:
            continue
        deg = to_deg(at)
        if what == "V":
            out.append(
                Violation(
                    "velocity_jump",
                    "continuity (V)",
                    f"the velocity jumps by {to_mm(jump):.4g} mm/rad at theta = {deg:.3f} deg: "
                    "an infinite acceleration (use laws that meet at the same velocity)",
                    ((deg, deg),),
                    abs(to_mm(jump)),
                )
            )
        else:
            out.append(
                Violation(
                    "acceleration_jump",
                    "continuity (A)",
                    f"the acceleration jumps by {to_mm(jump):.4g} mm/rad^2 at theta = "
                    f"{deg:.3f} deg: an infinite jerk (a law with zero end acceleration, or "
                    "limits.require_continuous_acceleration = false to accept it)",
                    ((deg, deg),),
                    abs(to_mm(jump)),
                )
            )
    return out


def accepted_jumps(design) -> str | None:
    """The acceleration jumps ``design`` accepts (limits.require_continuous_acceleration
    off) in words, or None: said beside the verdict, so that a design with an infinite
    jerk is not green without a word (a teacher's review: the same simple-harmonic law
    was amber in one design and green in another, nothing on screen saying why)."""
    from .motion import continuity_jumps, segments

    if design.limits.require_continuous_acceleration:
        return None
    at = sorted(
        to_deg(t) % 360.0 for t, what, _ in continuity_jumps(segments(design)) if what == "A"
    )
    if not at:
        return None
    where = ", ".join(f"{d:.3f}" for d in at[:6]) + (" ..." if len(at) > 6 else "")
    return (
        f"acceleration jumps accepted at theta = {where} deg (an infinite jerk): "
        "limits.require_continuous_acceleration is off"
    )


def _forces(a) -> list[Violation]:
    out, touching = [], a.in_contact.any(0)
    # F_N = 0 is contact kept, as machine.py's spring and jump-speed needs count it (a
    # dynamics review: a horizontal follower without preload rests on the low dwell at
    # F_t = 0; it was a jump, while the spring proposed for it, and the jump speed,
    # said it holds)
    bad = touching & (a.guide.FN < 0)
    worst = a.worst.get("FN_min")
    extra = worst.beyond(0.0, -1.0) if worst else ()
    if bad.any() or extra:
        low = min(float(a.guide.FN[bad].min()) if bad.any() else 0.0, worst.value if worst else 0.0)
        ranges = runs_deg(a.theta, bad, extra)
        out.append(
            Violation(
                "jump",
                "Eqs. 29-41",
                f"follower jump: contact force F_N = {low:.3g} N < 0 at {where_text(ranges)} "
                f"(raise the spring rate or preload, or lower the speed)",
                ranges,
                -low,
            )
        )
    lost = ~touching
    if lost.any():
        ranges = runs_deg(a.theta, lost)
        out.append(
            Violation(
                "contact_lost",
                "Eqs. 24, 26",  # the dwell's arc, beta - 2 psi, is shorter than nothing
                f"no face rests on the dwell arc at {where_text(ranges)}",
                ranges,
                float(lost.sum()),
            )
        )
    bad = _jammed(a)
    found = a.worst.get("guide_jam")  # between the samples (extremes.jam_worst)
    extra = found.beyond(0.0, 1.0) if found else ()
    if bad.any() or extra:
        ranges = runs_deg(a.theta, bad, extra)
        out.append(
            Violation(
                "guide_jam",
                "Eqs. 33-41",
                f"no guide-contact mode of Fig. 6 balances the follower with friction "
                f"mu = {a.design.dynamics.guide_friction:g} (self-locking) at {where_text(ranges)}",
                ranges,
                float(max(bad.sum(), 1)),  # (samples jammed; 1 for one found between)
            )
        )
    return out


def _train(a) -> list[Violation]:
    """The elastic follower train (camcore.train) leaves the cam where its contact force
    F_c <= 0: the dynamic jump, which a rigid analysis cannot see."""
    from .train import contact_force_fine

    r = a.train
    if r is None:
        return []
    if r.resonance:
        return [
            Violation(
                "dynamic_jump",
                "Eqs. 29-41, elastic train",
                f"the undamped elastic train resonates: its natural frequency "
                f"{r.natural_frequency / (2 * math.pi):.4g} Hz is harmonic {r.resonance} of "
                "the cam speed, so its vibration grows without bound and leaves the cam "
                "(add damping (dynamics.damping_ratio), or change the train stiffness)",
                ((0.0, 360.0),),
                1.0,  # (no finite "by how much": a flag, as profile_crossing's)
            )
        ]
    theta, Fc = contact_force_fine(r)  # between the samples too
    bad = Fc <= 0
    if not bad.any():
        return []
    ranges = runs_deg(theta, bad)
    low = float(Fc.min())
    return [
        Violation(
            "dynamic_jump",
            "Eqs. 29-41, elastic train",
            f"the elastic follower train leaves the cam: F_c = {low:.3g} N <= 0 at "
            f"{where_text(ranges)} (natural frequency "
            f"{r.natural_frequency / (2 * math.pi):.4g} Hz; "
            "stiffen the train, raise the spring, or slow down)",
            ranges,
            -low,
        )
    ]


def _jump_speed(a) -> list[Violation]:
    """The rigid follower's jump speed (camcore.machine, from Eq. 29: F_N has the sign
    of F_t in every guide mode that does not lock) against limits.min_jump_speed_ratio
    times the cam speed; unchecked without that limit (the ``jump`` rule holds at the
    speed itself; the elastic train's jump, ``dynamic_jump``, at the speed itself)."""
    from .machine import velocity_drop
    from .motion import segments

    lim = a.design.limits.min_jump_speed_ratio
    if lim is None:
        return []
    sp, speed = a.spring, a.design.cam.speed_rpm
    ratio = sp.jump_speed_rpm / speed
    if ratio >= least(lim):  # (never jumps: inf)
        return []
    drop = velocity_drop(segments(a.design))
    at = to_deg(sp.jump_at if drop is None else drop) % 360.0
    head = f"below the margin {lim:g} x the cam speed {speed:g} rpm (limits.min_jump_speed_ratio)"
    if drop is not None:  # no spring, no preload, no speed helps there (a review)
        said = (
            f"the velocity drops instantly at theta = {at:.1f} deg (an infinite "
            f"deceleration): the follower leaves the cam there at any speed, {head}; no "
            "spring holds it: a law without the drop (e.g. cycloidal) does"
        )
    elif ratio == 0.0:
        said = f"nothing holds the follower on the cam: it leaves it at any speed, {head}"
        said += f"; {_spring_for(a, sp.margin_rate, slower=False)}"
    else:  # the ratio rounded down, as the report's margin is (1.5999 is not "1.6")
        shown = math.floor(ratio * 100 * (1 + 1e-9)) / 100
        rpm = sp.jump_speed_rpm  # (in figures a crawling cam's 0.54 rpm keeps)
        rpm_text = f"{rpm:.0f}" if rpm >= 100 else f"{rpm:.3g}"
        said = (
            f"the follower leaves the cam at theta = {at:.1f} deg from {rpm_text} rpm, "
            f"{shown:.2f} x the cam speed, {head}: {_spring_for(a, sp.margin_rate)}"
        )
    ranges = ((at, at),) if ratio > 0 or drop is not None else ()
    return [Violation("jump_speed", "Eq. 29 (jump speed)", said, ranges, lim - ratio)]


def _spring_for(a, margin_rate: float | None, slower: bool = True) -> str:
    """What keeps the follower on the cam up to the margin's speed: the spring rate
    that does at the design's preload (machine.Spring.margin_rate, rounded up as
    machine.proposed_rate: the figure a user types in meets it), if any; more preload
    where there is a spring to load, a lower speed where some speed would do
    (``slower``; a review read both offered for a follower nothing held)."""
    from .machine import proposed_rate

    k = a.design.dynamics.spring_rate_N_per_m
    others = (["more preload"] if k > 0 else []) + (["a lower speed"] if slower else [])
    if margin_rate is None or not math.isfinite(margin_rate):
        return "no spring rate does at this preload: " + (
            " or ".join(others) if others else "a preload"
        )
    return (
        f"a spring rate of {proposed_rate(1.0, margin_rate):g} N/m or more does at this "
        f"preload (it is {k:g} N/m)" + "".join(f", or {o}" for o in others)
    )


def violation_mask(
    violations: list[Violation], theta_deg: np.ndarray, codes: set[str] | None = None
) -> np.ndarray:
    """Where on the angles ``theta_deg`` a limit is broken (any of ``codes``, or any
    limit at all): the union of the violations' angle ranges, ends included."""
    m = np.zeros(np.shape(theta_deg), bool)
    for v in violations:
        if codes is not None and v.code not in codes:
            continue
        for lo, hi in v.ranges_deg:
            m |= (theta_deg >= lo - 1e-9) & (theta_deg <= hi + 1e-9)
    return m


def hub_wall_mm(a) -> float | None:
    """The thinnest wall [mm] between the shaft bore (with its keyway, centred on +Y,
    camcore.export.bore_outline) and the cam; None without a bore.

    The distance between two polylines is the least of each one's vertices to the
    other's edges: against the round bore, the profile polyline's nearest approach to
    the axis less R; against the keyway, the profile's vertices to the slot (closed by
    the chord between its feet, which lies inside the bore and so never comes nearer)
    and the slot's corners and feet to the profile. The exact cam lies within the chord
    error of the polyline, which is subtracted."""
    from .toolpath import distance_to_polyline

    cam = a.design.cam
    R = cam.bore_diameter_mm / 2
    if R <= 0:
        return None
    p = to_mm(a.profile.points)
    reach = 2.0 * float(np.hypot(p[:, 0], p[:, 1]).max())  # beyond any distance here
    wall = float(distance_to_polyline(np.zeros((1, 2)), p, reach)[0]) - R
    if cam.keyway_width_mm > 0:
        hw, top = cam.keyway_width_mm / 2, R + cam.keyway_depth_mm
        foot = math.sqrt(R * R - hw * hw)
        slot = np.array([(-hw, foot), (-hw, top), (hw, top), (hw, foot)])
        wall = min(
            wall,
            float(distance_to_polyline(p, slot, reach).min()),
            float(distance_to_polyline(slot, p, reach).min()),
        )
    return wall - to_mm(a.chord_error)


def outer_diameter_mm(a) -> float:
    """The cam's outer diameter [mm], the stock it is cut from: twice its farthest
    vertex from the axis. That is the exact cam's farthest point: there the profile's
    normal passes through the axis, and the common normal passes through the instant
    centre I23 at q = V(theta) from it (Eq. 4), so only where V = 0: on a dwell (an arc
    about the axis) or at a rise's or fall's end, a station, where the grid and so the
    profile has a vertex. (Adding the chord error to the farthest vertex had overstated
    a roller cam's 190 mm as 190.0013, past a 190 mm limit; 1.1 mm at a 1 mm
    tolerance. A law whose V passes through 0 inside a segment is within the chord
    error of it.)"""
    p = a.profile.points
    return 2.0 * to_mm(float(np.hypot(p[:, 0], p[:, 1]).max()))


def _outer_diameter(a) -> list[Violation]:
    """The cam's size against limits.max_outer_diameter_mm (not in the paper: a
    designer's envelope, or a maker's stock)."""
    lim = a.design.limits.max_outer_diameter_mm
    if lim is None:
        return []
    size = outer_diameter_mm(a)
    if size <= lim + ROUND_OFF_MM:
        return []
    return [
        Violation(
            "outer_diameter",
            "cam size",
            f"the cam is {size:.4f} mm across, above the limit {lim:g} mm "
            f"(limits.max_outer_diameter_mm): {_smaller(a, (size - lim) / 2)}",
            (),
            size - lim,
        )
    ]


def _smaller(a, cut_mm: float) -> str:
    """How to make the cam ``cut_mm`` smaller in radius: the outer radius follows the
    base radius about one for one (0.9996-1.005 over the presets and followers), while
    there is that much base radius to take."""
    r_b = a.design.cam.base_radius_mm
    if cut_mm < r_b:
        return (
            f"about {cut_mm:.4g} mm less base radius (the outer radius follows r_b about "
            "one for one), or less lift"
        )
    return f"less base radius alone cannot (r_b is {r_b:g} mm): less lift, or a larger envelope"


def _hub_wall(a) -> list[Violation]:
    """The hub's thinnest wall against limits.min_hub_wall_mm (not in the paper: a
    maker's limit; a wall of hundredths of a millimetre passed every other check)."""
    wall, lim = hub_wall_mm(a), a.design.limits.min_hub_wall_mm
    if wall is None or wall >= lim - ROUND_OFF_MM:
        return []
    key = " and keyway" if a.design.cam.keyway_width_mm > 0 else ""
    return [
        Violation(
            "hub_wall",
            "hub wall",
            f"the thinnest wall between the bore{key} and the profile is {wall:.4f} mm, "
            f"below the limit {lim:g} mm (limits.min_hub_wall_mm): a hub that thin can "
            "crack when clamped or keyed; a smaller bore or a larger cam",
            (),
            lim - wall,
        )
    ]


def run_all(a, lift_error: float | None) -> list[Violation]:
    """Every violation of ``a`` (a camcore.analysis.Analysis)."""
    out = (
        _curvature_rules(a)
        + _pressure_angle(a)
        + _contact_stress(a)
        + _dwell_arcs(a)
        + rollers_apart(a)
        + _continuity(a)
        + _forces(a)
        + face_in_guide(a)
        + _train(a)
        + _jump_speed(a)
    )
    if not a.profile.is_star_shaped():
        out.append(
            Violation(
                "profile_crossing",
                "star-shaped profile",
                "the synthesized profile crosses itself (it is not star-shaped about the cam "
                "axis); no cam can be made from it",
                (),
                1.0,
            )
        )
    tol = a.design.limits.export_tolerance_mm
    if not to_mm(a.chord_error) <= tol:
        out.append(
            Violation(
                "export_tolerance",
                "export tolerance",
                f"the profile cannot be sampled within the export tolerance {tol * 1e3:.3g} um "
                f"with {a.profile.points.shape[0]} vertices: its chords stray up to "
                f"{to_mm(a.chord_error) * 1e3:.3g} um from the exact cam (cusps or folds)",
                (),
                to_mm(a.chord_error) - tol,
            )
        )
    out += _hub_wall(a) + _outer_diameter(a)
    if lift_error is not None and not lift_error <= lift_tolerance(a):
        out.append(
            Violation(
                "geometric_check",
                "Eqs. 1-20 (independent check)",
                f"rotating the finished cam gives a follower lift that differs from S(theta) "
                f"by up to {to_mm(lift_error):.4g} mm (allowed: the chord error over "
                f"cos(phi), {to_mm(lift_tolerance(a)):.3g} mm)",
                (),
                to_mm(lift_error),
            )
        )
    return out
