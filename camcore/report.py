"""Key numbers of an analysis in engineering units: the machine-readable contract
of ``camcore report --json`` (also used by the app and the tests), and the text
tables of ``camcore report`` and ``camcore compare``.
"""

from __future__ import annotations

import functools
import json
import math
import re

import numpy as np

from . import checks, machine, profile, train, wear
from .analysis import Analysis, analyze, compare, contacts
from .contact import hertz_validity
from .extremes import peak
from .model import (
    PAPER_FOLLOWERS,
    Design,
    FollowerKind,
    allowable_contact_stress_MPa,
    contact_stress_limit_MPa,
    edited_note,
    load_preset,
    omega_rad_s,
)
from .motion import FALL, HIGH, RISE, segment_word
from .units import to_um_per_mcycle

R2D = 180.0 / math.pi

# The paper's Table 1 (max F_N in the high dwell [N]) and its stress bounds (Fig. 13)
PAPER_TABLE1_N = {
    FollowerKind.single_roller: 133.496,
    FollowerKind.double_roller: 67.297,
    FollowerKind.single_concave: 129.161,
    FollowerKind.double_concave: 67.297,
}
# What Table 1's figure (F_N in the high dwell, Eqs. 29-41) depends on: the design's
# groups and fields that must be the paper example's for Table 1 to speak of it
TABLE1_INPUTS = ("motion", "follower", "dynamics", "cam.base_radius_mm", "cam.speed_rpm")


def _table1_inputs(design: Design) -> dict:
    data = design.model_dump(mode="json")
    data["follower"].pop("kind")  # Table 1 has a column per kind
    out = {}
    for path in TABLE1_INPUTS:
        group, _, name = path.partition(".")
        out[path] = data[group][name] if name else data[group]
    return out


@functools.lru_cache(maxsize=1)
def _paper_inputs() -> str:
    return json.dumps(_table1_inputs(load_preset("paper_example")), sort_keys=True)


def paper_table1_N(design: Design, kind: FollowerKind) -> float | None:
    """The paper's Table 1 value [N] for ``kind``, if ``design`` is the paper's own
    example in every input of that figure (TABLE1_INPUTS: not its name, follower kind,
    width, material or limits); None for another design (Table 1 says nothing of it:
    a review saw the paper's column beside a 120 mm cam) and for the followers the
    paper does not tabulate."""
    same = json.dumps(_table1_inputs(design), sort_keys=True) == _paper_inputs()
    return PAPER_TABLE1_N.get(kind) if same else None


def _max(x: np.ndarray, mask: np.ndarray | None = None) -> float | None:
    """The largest value, or None if there is none (no samples, or all undefined)."""
    x = x if mask is None else x[..., mask]
    x = x[~np.isnan(x)]
    return float(np.max(x)) if x.size else None


def _scaled(x: float | None, factor: float) -> float | None:
    return None if x is None else x * factor


def _range_mm(a: Analysis, part: int) -> list[float] | None:
    m = a.in_contact & (a.segment_code == part)
    if not m.any():
        return None
    rho = a.rho[m] * 1e3
    return [float(rho.min()), float(rho.max())]


def _radii_mm(a: Analysis) -> dict[str, float | None]:
    """The smallest convex radius of curvature rho > 0 and the tightest concave one
    |rho|, rho < 0 (Eq. 21, signed as profile.curvature_radius) over the contact
    windows of the whole cycle [mm]; None where the cam has no such stretch. A signed
    [min, max] (curvature_radius_mm) mixes the two on a roller cam with a concave
    flank; these are the figures a designer sizes with (the convex one sets the
    stress, the concave one the largest cutter and grinding wheel)."""
    convex, concave = profile.radius_extremes(a.rho, a.in_contact)
    return {"convex_min": _finite(convex, 1e3), "concave_min": _finite(concave, 1e3)}


def _flat_face_width_mm(a: Analysis) -> float | None:
    """A flat face must reach the contact wherever it wanders: X = -V about the axis,
    so a face symmetric about the stem needs width 2 max |V + stem_x| (plus the edge
    margin the designer adds). None for other followers."""
    if not a.geo.flat:
        return None
    x = -a.prog.V - a.geo.stem_x
    return 2.0 * float(np.max(np.abs(x))) * 1e3


def _face_contact_x_mm(a: Analysis) -> dict[str, list[float] | None]:
    """Where the contact runs on each face over the cycle: [min, max] of its X from the
    follower's axis [mm] (at the grid's samples), the stretch a concave pad or a flat
    face must cover, plus the margin the designer adds (a maker's review: a concave
    follower could not be sized from the report). None for a roller (it turns), a
    knife edge (the contact is its tip) and a face that never touches."""
    out: dict[str, list[float] | None] = {"face1": None, "face2": None}
    for i, f in enumerate(a.geo.faces):
        on = a.in_contact[i]
        if (a.geo.flat or f.r < 0) and on.any():
            x = (a.point_world[i, on, 0] - a.geo.stem_x) * 1e3
            out[f"face{i + 1}"] = [float(x.min()), float(x.max())]
    return out


def _classic_arcs(a: Analysis) -> dict:
    """Angles the high and low dwell arcs subtend on the cam (Eqs. 24, 26), for the
    paper's program; None for other programs (see ``dwells``)."""
    m = a.design.motion.classic
    if m is None:
        return {"high": None, "low": None}
    return {
        "high": m.high_dwell_deg - 2 * a.geo.psi_h * R2D,
        "low": m.low_dwell_deg + 2 * a.geo.psi_l * R2D,
    }


def _dwells(a: Analysis) -> list[dict]:
    """Every dwell of the program with its own arc (Eq. 20 radius, Eqs. 23/25 psi,
    Eqs. 24/26 the arc it subtends on the cam) and its Eq. 28 margin where it applies;
    dwells in a row at one displacement (also across theta = 0) are one dwell."""
    from .profile import arc_span, dwell_psi, dwell_runs

    out = []
    for j, (t0, t1) in dwell_runs(a.segments).items():  # dwells in a row: one dwell
        g = a.segments[j]
        start, end = arc_span(a.geo, a.segments, j)
        psi = dwell_psi(a.geo, g.S0)
        out.append(
            {
                "start_deg": (t0 * R2D) % 360.0,
                "angle_deg": (t1 - t0) * R2D,
                "S_mm": g.S0 * 1e3,
                "psi_deg": psi * R2D,
                "arc_deg": (end - start) * R2D,
            }
        )
    return out


def _event(
    k: int,
    names: list[str],
    before,
    after,
    seg_before: str,
    seg_after: str,
    next_motion: bool = False,
) -> str:
    """What happens at station k, in words (for a class): the segment that begins (its
    motion.segment_word; ``next_motion``: a rise or fall begins after another of the
    same word) and the faces that start or stop touching, and who carries the load from
    there."""
    parts = []
    if seg_before != seg_after:
        parts.append(f"the {seg_before} ends and the {seg_after} begins")
    elif next_motion:  # (a review read "nothing changes" where a rise met a rise)
        parts.append(f"one {seg_before} ends and the next begins")
    gained = [names[i] for i in range(len(names)) if after[i] and not before[i]]
    lost = [names[i] for i in range(len(names)) if before[i] and not after[i]]
    parts += [f"{n} touches" for n in gained] + [f"{n} leaves the cam" for n in lost]
    on = [names[i] for i in range(len(names)) if after[i]]
    if len(names) == 2 and len(on) == 2 and (gained or lost):
        parts.append("from here the load is shared (Eqs. 36-38)")
    elif len(names) == 2 and len(on) == 1 and (gained or lost):
        parts.append(f"from here {on[0]} carries the load alone")
    return f"station {k}: " + ("; ".join(parts) if parts else "nothing changes")


def _station_list(a: Analysis) -> list[dict]:
    """The stations in order, with the faces touching just after each and what happens
    there in words (``event``)."""
    names = [f.name.split(" ")[0] for f in a.geo.faces]
    two_pi = 2 * math.pi
    st, n = a.stations, a.stations.size
    x = np.mod(np.concatenate([st - 1e-7, st + 1e-7]), two_pi)
    both = contacts(a.design, a.geo, a.segments, x)  # the geometry alone, once
    before_in, after_in = both.in_contact[:, :n], both.in_contact[:, n:]
    index = [int(i) for i in both.prog.index]
    words = [segment_word(a.segments, i) for i in index]
    before_seg, after_seg = words[:n], words[n:]
    # a rise or fall that begins where another ends (not a run of dwells: one dwell)
    new_motion = [index[k] != index[n + k] and a.segments[index[n + k]].is_motion for k in range(n)]
    return [
        {
            "theta_deg": float(t * R2D),
            "contacts": [names[i] for i in range(len(names)) if after_in[i, k]],
            "event": (
                f"station {k}: the same angle as station {k - 1} (one contact: nothing to "
                "hand over)"
                if k > 0 and abs(t - st[k - 1]) < 1e-12
                else _event(
                    k,
                    names,
                    before_in[:, k],
                    after_in[:, k],
                    before_seg[k],
                    after_seg[k],
                    new_motion[k],
                )
            ),
        }
        for k, t in enumerate(st)
    ]


def _finite(x: float, factor: float = 1.0) -> float | None:
    """x * factor, or None where that is infinite (JSON has no infinity; a finite x can
    overflow in the new unit, e.g. a preload of 1e306 m in mm)."""
    y = x * factor
    return float(y) if math.isfinite(y) else None


def _machine(a: Analysis) -> dict:
    """Spring sizing, jump speed, shaft torque, power and flywheel (camcore.machine)."""
    sp, sh = a.spring, machine.shaft(a)
    return {
        "spring_rate_min_N_per_m": _finite(sp.rate_min),
        "preload_min_mm": _finite(sp.preload_min, 1e3),
        "spring_proposal": {
            "safety_factor": sp.safety_factor,
            "spring_rate_N_per_m": _finite(sp.proposed_rate),
            "preload_mm": a.design.dynamics.preload_mm,
        },
        "jump_speed_rpm": _finite(sp.jump_speed_rpm),
        "jump_margin": machine.margins(a.design, sp.rate_min, sp.jump_speed_rpm),
        "cam_torque_max_Nm": {"drive": sh.drive_max, "brake": sh.brake_max},
        "power_max_W": sh.power_max,
        "power_mean_W": sh.power_mean,
        "flywheel_energy_J": sh.flywheel_energy,
        "flywheel_inertia_kg_m2": _finite(sh.flywheel_inertia),
    }


def _hertz(a: Analysis) -> dict:
    """Contact half-width and where the line-contact formula is beyond its validity."""
    b, beyond = hertz_validity(a.design, a.FN, a.rho)
    return {
        "contact_half_width_max_mm": _scaled(_max(b), 1e3),
        "hertz_beyond_validity_deg": [
            list(r) for r in checks.runs_deg(a.theta, np.asarray(beyond.any(axis=0)))
        ],
    }


def _wear(a: Analysis) -> dict:
    """Archard wear along the profile and the pitting-life estimate (camcore.wear)."""
    _, depth = wear.along_profile(a)
    life = wear.pitting_life_cycles(a)
    revs_per_hour = a.design.cam.speed_rpm * 60.0
    return {
        "wear_depth_max_um_per_Mcycle": float(to_um_per_mcycle(depth.max())),
        "sliding_speed_max_m_per_s": float(wear.sliding_speed(a).max()),
        "pitting_life_cycles": _finite(life),
        "pitting_life_hours": _finite(life / revs_per_hour),
    }


def _train(a: Analysis) -> dict | None:
    """The elastic follower train's steady state (camcore.train); None when rigid."""
    r = a.train
    if r is None:
        return None
    w = omega_rad_s(a.design)
    head = {
        "natural_frequency_Hz": r.natural_frequency / (2 * math.pi),
        "frequency_ratio": r.natural_frequency / w,
        "resonant_harmonic": r.resonance or None,
    }
    if r.resonance:  # no steady state: no figures of one (never nan in the JSON)
        return {
            **head,
            "contact_force_min_N": None,
            "contact_force_max_N": None,
            "error_max_mm": None,
            "residual_vibration": [],
            "dynamic_jump_deg": [[0.0, 360.0]],
        }
    theta, Fc = train.contact_force_fine(r)  # between the samples too
    return {
        **head,
        "contact_force_min_N": float(Fc.min()),
        "contact_force_max_N": float(Fc.max()),
        "error_max_mm": float(np.abs(r.x - r.s).max()) * 1e3,
        "residual_vibration": train.residual_vibration(a.design, r),
        "dynamic_jump_deg": [list(x) for x in checks.runs_deg(theta, Fc <= 0)],
    }


def _pressure_angle_max_deg(a: Analysis, phi_deg: np.ndarray, code: int) -> float | None:
    """The largest pressure angle [deg] on the segments of kind ``code`` (RISE, FALL):
    their samples' ``phi_deg``, raised to the search's between them (extremes.Worst),
    as the check judges it (a CLI review: at 5 deg a figure of 9.52803 deg, under a
    limit of 9.5281, stood beside the violation of that limit)."""
    grid = _max(phi_deg)
    w = a.worst.get("pressure_angle_max")
    found = w.within(code, 1.0) if w is not None else None
    if grid is None or found is None or not math.isfinite(found):
        return grid
    return max(grid, math.degrees(found))


def summary(a: Analysis) -> dict:
    """The report of one analysis as a JSON-ready dict (see README for the keys)."""
    seg = a.prog.segment
    # the "high_dwell" figures: every dwell off the base circle (the paper's one high
    # dwell; a program rising in steps adds its middle dwells, which the app's words
    # call "the dwell at S = 8 mm": motion.segment_word)
    high = seg == HIGH
    two = high & (a.n_contacts == 2)
    phi = np.abs(a.pressure_angle) * R2D
    on = a.in_contact
    return {
        "design": a.design.name,
        "follower": a.design.follower.kind.value,
        "valid": a.valid,
        "violations": [v.as_dict() for v in a.violations],
        "unbounded": unbounded_of([v.code for v in a.violations], a.design.follower.kind),
        "dwell_radius_mm": a.geo.dwell_radius * 1e3,
        "psi_h_deg": a.geo.psi_h * R2D,
        "psi_l_deg": a.geo.psi_l * R2D,
        "stations_deg": [float(s) for s in a.stations * R2D],
        "dwell_arc_deg": _classic_arcs(a),
        "dwells": _dwells(a),
        "stations": _station_list(a),
        "pressure_angle_max_deg": {
            "rise": _pressure_angle_max_deg(a, phi[on & (a.segment_code == RISE)], RISE),
            "fall": _pressure_angle_max_deg(a, phi[on & (a.segment_code == FALL)], FALL),
        },
        "curvature_radius_mm": {"rise": _range_mm(a, RISE), "fall": _range_mm(a, FALL)},
        "radius_of_curvature_mm": _radii_mm(a),
        # the cycle's maxima between the samples too (extremes.peak), as the checks
        # judge them; a dwell's values are constant on each of its contact windows
        "contact_force_max_N": {
            "cycle": peak(a, "FN_max", _max(a.guide.FN)),
            "high_dwell": _max(a.guide.FN, high),
            "high_dwell_two_contact": _max(a.guide.FN, two),
        },
        "guide_force_max_N": {
            "F1": peak(a, "F1_max", _max(a.guide.F1)),
            "F2": peak(a, "F2_max", _max(a.guide.F2)),
        },
        "contact_stress_max_MPa": {
            "cycle": _scaled(peak(a, "stress_max", _max(a.stress)), 1e-6),
            "high_dwell": _scaled(_max(a.stress[:, high]), 1e-6) if high.any() else None,
            # while both faces of a double follower touch (the load shared): where the
            # paper's lower stress shows (a teacher's review: the cycle's peak, in the
            # one-face windows, hid it)
            "high_dwell_two_contact": _scaled(_max(a.stress[:, two]), 1e-6),
        },
        **_hertz(a),
        "contact_stress_allowable_MPa": allowable_contact_stress_MPa(a.design),
        "contact_stress_safety_factor": a.design.limits.contact_stress_safety_factor,
        "total_load_high_dwell_N": _max(a.Ft, high),
        "flat_face_width_min_mm": _flat_face_width_mm(a),
        "face_contact_x_mm": _face_contact_x_mm(a),
        **_machine(a),
        **_wear(a),
        "train": _train(a),
        "profile": {
            "area_mm2": a.profile.area * 1e6,
            "perimeter_mm": a.profile.perimeter * 1e3,
            "vertices": int(a.profile.points.shape[0]),
            "outer_diameter_mm": checks.outer_diameter_mm(a),
            "hub_wall_mm": checks.hub_wall_mm(a),  # None without a bore
        },
        "verification": {
            "max_lift_error_mm": None if a.lift_error is None else a.lift_error * 1e3,
            "allowed_lift_error_mm": checks.lift_tolerance(a) * 1e3,
            "export_tolerance_mm": a.design.limits.export_tolerance_mm,
            "chord_error_mm": a.chord_error * 1e3,
        },
    }


# a row with no value at all ("- mm", "- / - N"): "-" alone, no unit on nothing
_NO_VALUE = re.compile(r"^-( / -)* [^\d]*$")


BIG = 1e7  # beyond it a figure prints in significant figures, not fixed decimals


def _fmt(x, nd=3) -> str:
    if x is None:
        return "-"
    if isinstance(x, list):
        return " .. ".join(_fmt(v, nd) for v in x)
    if abs(x) >= BIG:  # (a review: "9802731368133097947136.000000 kg m2" at 1e-9 rpm)
        return f"{x:.4g}"
    return f"{x:.{nd}f}".replace(f"-{0:.{nd}f}", f"{0:.{nd}f}")  # no "-0.00 W"


def _fmt_against(x, limit: float | None, nd: int) -> str:
    """_fmt, with more places where ``nd`` would print the ``limit`` itself for a value
    that is not it (a designer's review read a valid 29.999 deg as "30.00" beside the
    30 deg limit)."""
    text = _fmt(x, nd)
    if x is None or limit is None or abs(x - limit) <= checks.ROUND_OFF * abs(limit):
        return text  # (the limit itself, to round-off: it meets it, checks.most)
    for places in range(nd, nd + 7):  # (at most 6 places more)
        text = _fmt(x, places)
        if text != _fmt(limit, places):
            break
    return text


def _train_text(t: dict | None) -> str:
    """The elastic train's row of ``machine_rows``."""
    if t is None:
        return "rigid (dynamics.train_stiffness_N_per_m not set)"
    if t["resonant_harmonic"]:
        return (
            f"f_n = {t['natural_frequency_Hz']:.4g} Hz = harmonic {t['resonant_harmonic']} "
            "of the cam speed, undamped: resonant, no steady state"
        )
    residual = ", ".join(f"{v['amplitude_mm']:.3g}" for v in t["residual_vibration"])
    return (
        f"f_n = {t['natural_frequency_Hz']:.4g} Hz ({t['frequency_ratio']:.3g} x cam speed), "
        f"F_c {t['contact_force_min_N']:.4g} .. {t['contact_force_max_N']:.4g} N, "
        f"error max {t['error_max_mm']:.3g} mm, residual {residual} mm"
    )


def _down(x: float) -> str:
    """A margin to 2 decimals, rounded down: 1.4996 is '1.49', not '1.5' beside a
    warning that it is below 1.5 (round-off aside: 0.3 / 0.1 is 2.9999999999999996)."""
    if x >= BIG:  # (a review: "jumps at 1009989342029.04 x this speed")
        return f"{x:.3g}"
    return f"{math.floor(x * (1 + machine.ROUND_OFF) * 100) / 100:.2f}"


def _margin_text(s: dict) -> str:
    """k / k_min and jump speed / running speed, flagged below the safety factor n."""
    m, n = s["jump_margin"], s["spring_proposal"]["safety_factor"]
    if m["jump_speed"] == 0.0:  # a jump speed of 0 (machine.velocity_drop, or no hold)
        return "none: the follower leaves the cam at any speed"
    parts = []
    if m["spring_rate"] is not None:
        parts.append(f"k = {_down(m['spring_rate'])} k_min")
    if m["jump_speed"] is not None:
        parts.append(f"jumps at {_down(m['jump_speed'])} x this speed")
    text = ", ".join(parts) or "-"
    rate = m["spring_rate"]
    if rate is not None and rate < 1.0 - machine.ROUND_OFF:
        text += " (below k_min: the follower jumps)"
    elif rate is not None and rate < n * (1 - machine.ROUND_OFF):
        text += f" (below the safety factor {n:g}: close to jump)"
    return text


def jump_speed_text(rpm: float | None) -> str:
    """A summary's ``jump_speed_rpm`` in words (None: it never jumps)."""
    if rpm is None:
        return "never (nothing pulls the follower off)"
    if rpm == 0.0:  # (an instant drop in V, machine.velocity_drop, or nothing holding it)
        return "at any speed"
    return f"{_fmt(rpm, 1)} rpm"


def machine_rows(s: dict) -> list[tuple[str, str]]:
    """The running machine's figures of a summary as (label, value) rows: the text
    report and the app's key numbers show the same lines."""
    k_min, prop = s["spring_rate_min_N_per_m"], s["spring_proposal"]
    n, k = prop["safety_factor"], prop["spring_rate_N_per_m"]
    # n k_min is rounded up to 3 digits (machine.proposed_rate); a proposal above it
    # is the rate limits.min_jump_speed_ratio asks (a review read "safety factor 1.5"
    # beside 2.06 k_min)
    by_margin = k_min and k is not None and k > 1.01 * n * k_min
    spring = (
        f"{_fmt(k_min, 1)} / {_fmt(k, 1)} N/m (preload {prop['preload_mm']:g} mm, "
        + (
            "the rate the min jump-speed ratio asks: above safety factor "
            if by_margin
            else "safety factor "
        )
        + f"{n:g})"
    )
    if s["spring_rate_min_N_per_m"] is None:  # (inf: see machine.spring_rate_min)
        spring = "no spring rate keeps contact at this preload"
    elif s["spring_rate_min_N_per_m"] == 0.0:  # (a review read "0.0 / 0.0" as an omission)
        spring = (
            "none needed: nothing pulls the follower off the cam"
            if s["jump_speed_rpm"] is None
            # (its weight, or an external load F_e toward the cam: a review's g = 0)
            else "none needed at this speed: the follower's weight and any external load "
            "keep it on the cam"
        )
    free = unbounded_figures(s)
    return [
        ("spring rate min / proposed", spring),
        ("preload min at this rate", f"{_fmt(s['preload_min_mm'], 3)} mm"),
        (
            "jump speed",
            jump_speed_text(s["jump_speed_rpm"]),
        ),
        ("margin to jump", _margin_text(s)),
        (
            "shaft torque drive / brake",
            "unbounded"
            if "torque" in free
            else f"{_fmt(s['cam_torque_max_Nm']['drive'])} / "
            f"{_fmt(s['cam_torque_max_Nm']['brake'])} N m",
        ),
        (
            "power max / mean",
            "unbounded"
            if "power" in free
            else f"{_fmt(s['power_max_W'], 1)} / {_fmt(s['power_mean_W'], 2)} W",
        ),
        (
            "flywheel energy / inertia",
            "unbounded"
            if "flywheel" in free
            else f"{_fmt(s['flywheel_energy_J'], 4)} J / "
            f"{_fmt(s['flywheel_inertia_kg_m2'], 6)} kg m2",
        ),
        (
            "wear depth max (Archard)",
            # (a designer's review read "0.0000 um ... sliding up to 0.00 m/s" of rollers)
            "none: a roller rolls (no sliding wear to model)"
            if FollowerKind(s["follower"]).is_roller
            else "unbounded"
            if "wear" in free
            else f"{_fmt(s['wear_depth_max_um_per_Mcycle'], 4)} um per "
            f"million cycles (sliding up to {_fmt(s['sliding_speed_max_m_per_s'], 2)} m/s)",
        ),
        (
            "pitting life",
            "none to estimate: the contact stress has no bound"
            if "life" in free
            else _life_text(s["follower"], long=True, allowable=s["contact_stress_allowable_MPa"])
            if s["pitting_life_cycles"] is None
            else f"{s['pitting_life_cycles']:.3g} cycles ({s['pitting_life_hours']:.3g} h)",
        ),
        (
            "elastic train",
            _train_text(s["train"]),
        ),
    ]


def inputs_text(design) -> str:
    """The design's inputs in a few lines: the motion program segment by segment, the
    follower, the cam, the dynamics and the material (a review: a report of a teacher's
    own program had not said which program it was; another: the CLI's text report
    showed no input, so a value a file had left out went unseen)."""
    f, c, dyn, m = design.follower, design.cam, design.dynamics, design.material
    parts = []
    for i, g in enumerate(design.motion.segments, start=1):
        law = g.law.value if g.law is not None else "cycloidal"
        lift = "" if g.kind.value == "dwell" else f" {g.lift_mm:g} mm {law}"
        parts.append(f"{i}. {g.kind.value} {g.angle_deg:g} deg{lift}")
    used = [
        f"{label} {getattr(f, key):g} mm"
        for key, label in (
            ("roller_radius_mm", "r_c"),
            ("face_radius_mm", "r_f"),
            ("offset_mm", "e"),
            ("single_offset_mm", "e_s"),
        )
        if f.kind.uses(key)
    ]
    lines = [
        ("program", "; ".join(parts)),
        ("follower", ", ".join([f.kind.label, *used])),
        (
            "cam",
            f"r_b {c.base_radius_mm:g} mm, width {c.width_mm:g} mm, {c.speed_rpm:g} rpm, "
            f"bore {c.bore_diameter_mm:g} mm",
        ),
        (
            "dynamics",
            f"M {dyn.mass_g:g} g, k {dyn.spring_rate_N_per_m:g} N/m, s_p {dyn.preload_mm:g} "
            f"mm, guide mu {dyn.guide_friction:g}, d {dyn.guide_width_mm:g} mm, "
            f"l1 {dyn.overhang_mm:g} mm, l2 {dyn.guide_length_mm:g} mm"
            + (f", contact mu {dyn.contact_friction:g}" if dyn.contact_friction else "")
            + (f", external load {dyn.external_load_N:g} N" if dyn.external_load_N else "")
            # what else the figures depend on (a designer's review could not reproduce
            # the jump speed from "M 800 g": the analysis moves M + m_s / 3)
            + (f", spring mass {dyn.spring_mass_g:g} g" if dyn.spring_mass_g else "")
            + f", g {dyn.gravity_m_s2:g} m/s2"
            + (
                f", train k1 {dyn.train_stiffness_N_per_m:g} N/m zeta {dyn.damping_ratio:g}"
                if dyn.train_stiffness_N_per_m
                else ""
            ),
        ),
        (
            "material",
            f"cam {design.material.grade.value.replace('_', ' ')} (allowable "
            f"{allowable_contact_stress_MPa(design):g} MPa / safety factor "
            f"{design.limits.contact_stress_safety_factor:g}), E {m.cam_E_GPa:g} GPa "
            f"nu {m.cam_nu:g}; follower E {m.follower_E_GPa:g} GPa nu {m.follower_nu:g}",
        ),
        ("limits", _limits_text(design)),
        ("making", _making_text(c)),
    ]
    width = max(len(k) for k, _ in lines)
    return "\n".join(f"{k.ljust(width)}  {v}" for k, v in lines)


def _limits_text(design) -> str:
    """The limits the design is checked against (a designer's review: the printable
    report said "all limits met" without saying which)."""
    lim = design.limits
    acc = "continuous" if lim.require_continuous_acceleration else "jumps accepted"
    d_max = lim.max_outer_diameter_mm
    size = "" if d_max is None else f"outer diameter <= {d_max:g} mm, "
    # (a knife edge has no Hertz stress to judge: Eq. 42 needs a radius)
    knife = design.follower.kind is FollowerKind.knife_edge
    sigma = "" if knife else f"sigma_H <= {contact_stress_limit_MPa(design):g} MPa, "
    return (
        f"|phi| <= {lim.max_pressure_angle_deg:g} deg, {sigma}hub wall >= "
        f"{lim.min_hub_wall_mm:g} mm (with a bore), {size}profile within "
        f"{lim.export_tolerance_mm:g} mm, acceleration {acc}; {_no_jump_text(design)}"
    )


def _no_jump_text(design) -> str:
    """The jump rule: at the cam speed, or up to the margin limits.min_jump_speed_ratio."""
    speed, m = design.cam.speed_rpm, design.limits.min_jump_speed_ratio
    if m is None:
        return f"no jump at {speed:g} rpm"
    return f"no jump up to {m:g} x {speed:g} = {m * speed:.6g} rpm"


def _making_text(c) -> str:
    """The cam's making inputs: the keyway and the G-code's cutter, passes, feeds and
    heights (a maker's review: the report that goes to the shop had only the bore)."""
    keyway = (
        f"keyway {c.keyway_width_mm:g} x {c.keyway_depth_mm:g} mm"
        if c.keyway_width_mm > 0
        else f"D-flat bore, {c.bore_flat_mm:g} mm across"
        if c.bore_flat_mm > 0
        else "no keyway"
    )
    passes = "1 pass" if c.passes == 1 else f"{c.passes} passes"
    spindle = f"{c.spindle_rpm:g} rpm" if c.spindle_rpm > 0 else "not given"
    return (
        f"{keyway}; G-code: cutter {c.cutter_diameter_mm:g} mm, {passes}, breakthrough "
        f"{c.breakthrough_mm:g} mm, feed {c.feed_mm_per_min:g} / plunge "
        f"{c.plunge_mm_per_min:g} mm/min, spindle {spindle}, rapids {c.safe_height_mm:g} mm"
    )


def _unbounded(s: dict, codes, what: str, grows: str) -> str | None:
    """The note of unbounded_notes for the violations ``codes`` of summary ``s``, or
    None: ``what`` happens where they are, and ``grows`` without bound toward it, so the
    cycle's maxima are the samples' largest, set by the grid, not by the cam."""
    ranges = checks.merged_deg(
        r for v in s["violations"] if v["code"] in codes for r in v["ranges_deg"]
    )
    if not ranges:
        return None
    return (
        f"{what} at {checks.where_text(tuple(ranges))}: toward it {grows} without bound, "
        "so their maxima are the samples' largest, not the cam's"
    )


def jam_note(s: dict) -> str | None:
    """Where the guide jams (self-locking: Eqs. 33-41 have no mode with F1, F2 >= 0):
    toward it the forces grow without bound (a review read '8690819489.753 N' as a
    figure)."""
    return _unbounded(
        s,
        UNBOUNDED_BY["the guide jams"],
        "the guide jams (self-locking)",
        "the force, stress, torque and power grow",
    )


def cusp_note(s: dict) -> str | None:
    """Where the profile has a cusp or folds back (its radius of curvature reaches 0):
    the Hertz stress (Eq. 42) grows without bound toward rho = 0 (a teacher's review
    read 'sigma_H <= 1957662.6 / 800 MPa')."""
    return _unbounded(
        s,
        UNBOUNDED_BY["the cam has a cusp"],
        "the profile has a cusp or folds back",
        "the contact stress grows",
    )


def impulse_note(s: dict) -> str | None:
    """Where the velocity jumps (an infinite acceleration): the cam strikes the
    follower (a jump up: an infinite force) or drops it (down: it leaves the cam), and
    no grid sample sees it (a review: a constant-velocity rise's figures read as
    bounds)."""
    return _unbounded(
        s,
        UNBOUNDED_BY["the velocity jumps"],
        "the velocity jumps (an infinite acceleration)",
        "the forces, stress, torque and power grow",
    )


# what has no bound for each reason of unbounded_notes (the figures its note names)
UNBOUNDED = {
    # (F1, F2 are linear in F_t, the torque is F_N times its lever; an impulse's energy,
    # the flywheel's, is finite; a sliding face's wear grows with F_N, and at a cusp with
    # 1 / u as the contact stalls on the cam: camcore.wear; a roller's is 0)
    "the velocity jumps": {"force", "guide", "stress", "torque", "power", "life", "wear"},
    "the cam has a cusp": {"stress", "life", "wear"},
    "the guide jams": {
        "force",
        "guide",
        "stress",
        "torque",
        "power",
        "flywheel",
        "life",
        "wear",
    },
}


def unbounded_figures(s: dict) -> set[str]:
    """Which cycle figures of summary ``s`` have no bound (UNBOUNDED's names: force,
    guide, stress, torque, power, flywheel, life): the text shows "unbounded" there, not
    the samples' largest (a designer's review read "101036570.5 MPa" in the key numbers
    beside a headline of "unbounded"). The JSON keeps the numbers, the notes, and
    these names as ``unbounded``."""
    return set(unbounded_of([v["code"] for v in s["violations"]], s["follower"]))


# the violation codes behind each reason of unbounded_notes
UNBOUNDED_BY = {
    "the velocity jumps": {"velocity_jump"},
    "the cam has a cusp": checks.CUSPED,
    "the guide jams": {"guide_jam"},
}


def unbounded_of(codes: list[str], follower: str) -> list[str]:
    """The figures (UNBOUNDED's names, sorted) that the violations ``codes`` leave
    without bound for a ``follower`` (FollowerKind's value; a roller has no sliding
    wear at all): a post-processor of a sweep's table reads them beside the numbers (a
    review: a cusp's 28,672,817 MPa read as a stress; another a face's wear of 20,220
    um per million cycles)."""
    found = {f for why, by in UNBOUNDED_BY.items() if by & set(codes) for f in UNBOUNDED[why]}
    return sorted(found - ({"wear"} if FollowerKind(follower).is_roller else set()))


def bounded(x, nd: int, figure: str, unbounded: set[str]) -> str:
    """_fmt, or "unbounded" if ``figure`` is among ``unbounded`` (unbounded_figures)."""
    return "unbounded" if figure in unbounded else _fmt(x, nd)


def unbounded_notes(s: dict) -> list[tuple[str, str]]:
    """(why, note) for each reason the cycle's force or stress maxima have no bound:
    an impulse (impulse_note), a cusp (cusp_note), a jammed guide (jam_note)."""
    found = (
        ("the velocity jumps", impulse_note(s)),
        ("the cam has a cusp", cusp_note(s)),
        ("the guide jams", jam_note(s)),
    )
    return [(why, note) for why, note in found if note is not None]


def _face_x_text(s: dict) -> str:
    """face_contact_x_mm as "lo .. hi mm"; a double follower's faces named (S1, S2:
    one of them may never touch)."""
    double = FollowerKind(s["follower"]).is_double
    shown = [
        f"{f'S{i} ' if double else ''}{_fmt(v[0], 2)} .. {_fmt(v[1], 2)}"
        for i, v in enumerate(s["face_contact_x_mm"].values(), start=1)
        if v is not None
    ]
    return " / ".join(shown) + " mm" if shown else "-"


def rho_range_text(rng: list[float] | None, fmt, folds: bool = False) -> str:
    """A signed rho range [mm] as "min .. max mm", or, where rho changes sign (it passes
    through infinity at an inflection, so its ends say nothing), that it does (a
    designer's review read "-5148 .. 24045 mm"); through 0 where the profile ``folds``
    back (folds_back), which is no inflection (a teacher's review)."""
    if rng is not None and rng[0] < 0 < rng[1]:
        if folds:
            return "changes sign through 0: the profile folds back (a cusp)"
        return "changes sign (an inflection): see convex / concave min"
    return f"{fmt(rng, 2)} mm"


def folds_back(s: dict) -> bool:
    """Whether summary ``s`` breaks a limit of a profile with a cusp or folding back
    (checks.CUSPED): its radius of curvature passes through 0, not through infinity."""
    return any(v["code"] in checks.CUSPED for v in s["violations"])


def _psi_text(s: dict) -> str:
    """psi_h / psi_l, or a dash for a single follower, as for every figure that does
    not apply: its one contact hands over to nothing (Eqs. 23, 25 are about two faces;
    the summary keeps their 0)."""
    if not FollowerKind(s["follower"]).is_double:
        return "-"
    return f"{_fmt(s['psi_h_deg'], 4)} / {_fmt(s['psi_l_deg'], 4)} deg"


def _stations_text(stations_deg: list[float]) -> str:
    """The stations, each angle once: a single follower's pairs coincide (its psi = 0)."""
    shown: list[str] = []
    for v in stations_deg:
        word = f"{v:.3f}"
        if not shown or shown[-1] != word:
            shown.append(word)
    # (round-off aside: a dwell of exactly 4 psi put station 3 1e-14 rad before 2, and
    # a valid design read "shorter than 4 psi": an adversarial review)
    swapped = [
        i
        for i in range(1, len(stations_deg))
        if stations_deg[i] < stations_deg[i - 1] - checks.ROUND_OFF * abs(stations_deg[i - 1])
    ]
    note = "".join(  # (a designer's review: "158.064 141.936" said nothing of why)
        f" (station {i} before {i - 1}: the dwell between them is shorter than 4 psi, Eq. 28)"
        for i in swapped
    )
    return " ".join(shown) + " deg" + note


def report_text(s: dict, design: Design | None = None) -> str:
    """A readable table of one summary, under the ``design``'s inputs if given."""
    limit = None if design is None else design.limits.max_pressure_angle_deg
    free = unbounded_figures(s)
    rho = s["curvature_radius_mm"]
    rows = [
        ("follower", s["follower"]),
        ("valid", "yes" if s["valid"] else "NO"),
        ("high-dwell radius R (Eq. 20)", f"{_fmt(s['dwell_radius_mm'], 4)} mm"),
        ("psi_h / psi_l (Eqs. 23, 25)", _psi_text(s)),
        ("stations", _stations_text(s["stations_deg"])),
        (
            "dwell arcs high / low (Eqs. 24, 26)",
            f"{_fmt(s['dwell_arc_deg']['high'], 3)} / {_fmt(s['dwell_arc_deg']['low'], 3)} deg",
        ),
        (
            "dwells (start: angle, arc)",
            "; ".join(
                f"{d['start_deg']:.1f}: {d['angle_deg']:.1f}, {d['arc_deg']:.2f} deg"
                for d in s["dwells"]
            )
            or "-",
        ),
        (
            "max pressure angle rise / fall",
            f"{_fmt_against(s['pressure_angle_max_deg']['rise'], limit, 2)} / "
            f"{_fmt_against(s['pressure_angle_max_deg']['fall'], limit, 2)} deg",
        ),
        ("rho rise (min .. max)", rho_range_text(rho["rise"], _fmt, folds_back(s))),
        ("rho fall (min .. max)", rho_range_text(rho["fall"], _fmt, folds_back(s))),
        (
            "rho convex min / concave min",
            f"{_fmt(s['radius_of_curvature_mm']['convex_min'], 2)} / "
            f"{_fmt(s['radius_of_curvature_mm']['concave_min'], 2)} mm",
        ),
        (
            "max F_N cycle / high dwell",
            f"{bounded(s['contact_force_max_N']['cycle'], 3, 'force', free)} / "
            f"{_fmt(s['contact_force_max_N']['high_dwell'])} N",
        ),
        (
            "max F_N two-contact high dwell",
            f"{_fmt(s['contact_force_max_N']['high_dwell_two_contact'])} N",
        ),
        (
            "max F1 / F2",
            "unbounded"
            if "guide" in free
            else f"{_fmt(s['guide_force_max_N']['F1'])} / {_fmt(s['guide_force_max_N']['F2'])} N",
        ),
        (
            "max stress cycle / high dwell",
            f"{bounded(s['contact_stress_max_MPa']['cycle'], 2, 'stress', free)} / "
            f"{_fmt(s['contact_stress_max_MPa']['high_dwell'], 2)} MPa",
        ),
        (
            "contact half-width max",
            f"{_fmt(s['contact_half_width_max_mm'], 4)} mm"
            + (
                ""
                if not s["hertz_beyond_validity_deg"]
                else "; Hertz beyond validity at "
                + checks.where_text(tuple(map(tuple, s["hertz_beyond_validity_deg"])))
                + " (conservative stress used)"
            ),
        ),
        ("flat face width needed", f"{_fmt(s['flat_face_width_min_mm'], 3)} mm"),
        ("face contact x from the axis", _face_x_text(s)),
        (
            "allowable stress / safety factor",
            f"{s['contact_stress_allowable_MPa']:g} MPa / {s['contact_stress_safety_factor']:g}",
        ),
        *machine_rows(s),
        (
            "profile area / perimeter",
            f"{_fmt(s['profile']['area_mm2'], 2)} mm2 / {_fmt(s['profile']['perimeter_mm'], 3)} mm",
        ),
        ("outer diameter (stock)", f"{_fmt(s['profile']['outer_diameter_mm'], 3)} mm"),
        *(
            [("hub wall (thinnest, bore to profile)", f"{_fmt(s['profile']['hub_wall_mm'], 3)} mm")]
            if s["profile"]["hub_wall_mm"] is not None
            else []
        ),
        (
            "profile chords within",
            f"{s['verification']['chord_error_mm']:.3g} mm of the "
            f"exact cam (tolerance {s['verification']['export_tolerance_mm']:g} mm)",
        ),
        (
            "geometric check max |lift - S|",
            f"{s['verification']['max_lift_error_mm']:.3g} mm (allowed "
            f"{s['verification']['allowed_lift_error_mm']:.3g} mm)"
            if s["verification"]["max_lift_error_mm"] is not None
            else "-",
        ),
    ]
    w = max(len(k) for k, _ in rows)
    lines = [f"{s['design']}", ""]
    if design is not None:
        if (edited := edited_note(design)) is not None:
            lines[1:1] = [f"({edited})"]
        lines += [f"  {line}" for line in inputs_text(design).splitlines()] + [""]
    lines += [f"  {k:<{w}}  {_NO_VALUE.sub('-', v)}" for k, v in rows]
    for _, note in reversed(unbounded_notes(s)):
        lines.insert(lines.index(f"  {'valid':<{w}}  NO") + 1, f"  !! {note}")
    for v in s["violations"]:
        lines.append(f"  ! {v['equation']}: {v['message']}")
    if design is not None and (accepted := checks.accepted_jumps(design)) is not None:
        lines.append(f"  ~ {accepted}")
    return "\n".join(lines)


def compare_rows(design: Design, kinds: tuple[FollowerKind, ...] = PAPER_FOLLOWERS) -> list[dict]:
    """Table 1 quantities and the stress maxima for each follower in ``kinds`` (default
    the paper's four; ``paper_table1_N``: the paper's figure, for its own example only,
    see paper_table1_N)."""
    rows = []
    for kind, a in compare(design, verify=True, kinds=kinds).items():
        assert not isinstance(a, str)  # compare raises (errors=False) on a bad follower
        s = summary(a)
        rows.append(
            {
                "follower": kind.value,
                "valid": s["valid"],
                "breaks": sorted({f"{v.code} ({v.equation})" for v in a.violations}),
                # figures without a bound (a jam, a cusp, a velocity jump): said beside
                # them (a designer's review read 2,004,164 MPa in the table unflagged)
                "unbounded": [note for _, note in unbounded_notes(s)],
                "unbounded_figures": sorted(unbounded_figures(s)),  # (UNBOUNDED's names)
                "FN_high_dwell_N": s["contact_force_max_N"]["high_dwell"],
                "FN_high_dwell_two_contact_N": s["contact_force_max_N"]["high_dwell_two_contact"],
                "paper_table1_N": paper_table1_N(design, kind),
                "FN_cycle_N": s["contact_force_max_N"]["cycle"],
                "pressure_angle_rise_deg": s["pressure_angle_max_deg"]["rise"],
                "pressure_angle_fall_deg": s["pressure_angle_max_deg"]["fall"],
                "rho_convex_min_mm": s["radius_of_curvature_mm"]["convex_min"],
                "rho_concave_min_mm": s["radius_of_curvature_mm"]["concave_min"],
                "outer_diameter_mm": s["profile"]["outer_diameter_mm"],
                "F1_max_N": s["guide_force_max_N"]["F1"],
                "F2_max_N": s["guide_force_max_N"]["F2"],
                "stress_max_MPa": s["contact_stress_max_MPa"]["cycle"],
                "stress_high_dwell_MPa": s["contact_stress_max_MPa"]["high_dwell"],
                "stress_high_dwell_two_contact_MPa": s["contact_stress_max_MPa"][
                    "high_dwell_two_contact"
                ],
                "max_lift_error_mm": s["verification"]["max_lift_error_mm"],
                "wear_depth_max_um_per_Mcycle": s["wear_depth_max_um_per_Mcycle"],
                "pitting_life_cycles": s["pitting_life_cycles"],
                "spring_rate_min_N_per_m": s["spring_rate_min_N_per_m"],
                "jump_speed_rpm": s["jump_speed_rpm"],
                "cam_torque_drive_max_Nm": s["cam_torque_max_Nm"]["drive"],
            }
        )
    return rows


# compare_rows' cycle figures and their names in UNBOUNDED (the dwell's are bounded)
_FIGURE_OF = {
    "FN_cycle_N": "force",
    "F1_max_N": "guide",
    "F2_max_N": "guide",
    "stress_max_MPa": "stress",
}


def compare_text(rows: list[dict]) -> str:
    head = (
        "follower",
        "FN dwell",
        "FN 2-contact",
        "Table 1",
        "FN cycle",
        "|F1|max",
        "|F2|max",
        "sigma max",
        "sigma dwell",
        "sigma 2-cont.",
    )
    keys = (
        "FN_high_dwell_N",
        "FN_high_dwell_two_contact_N",
        "paper_table1_N",
        "FN_cycle_N",
        "F1_max_N",
        "F2_max_N",
        "stress_max_MPa",
        "stress_high_dwell_MPa",
        "stress_high_dwell_two_contact_MPa",
    )
    lines = [
        "  ".join(f"{h:>14}" for h in head),
        "  ".join(f"{u:>14}" for u in ("", "N", "N", "N", "N", "N", "N", "MPa", "MPa", "MPa")),
    ]
    for r in rows:  # a figure with no bound says so (a review read 3019079.610 MPa)
        free = set(r["unbounded_figures"])
        shown = (bounded(r[k], 3, _FIGURE_OF.get(k, ""), free) for k in keys)
        lines.append(f"{r['follower']:>14}  " + "  ".join(f"{c:>14}" for c in shown))
    tabulated = [r for r in rows if FollowerKind(r["follower"]) in PAPER_TABLE1_N]
    if tabulated and all(r["paper_table1_N"] is None for r in tabulated):
        lines.append(
            "(Table 1: the paper's figures for its own example, shown for the paper_example "
            "design only: this one differs from it)"
        )
    # the geometry, where the followers differ most (a designer's review: not shown)
    head3 = (
        "follower",
        "phi max rise",
        "phi max fall",
        "rho convex min",
        "rho concave min",
        "outer diameter",
    )
    keys3 = (
        "pressure_angle_rise_deg",
        "pressure_angle_fall_deg",
        "rho_convex_min_mm",
        "rho_concave_min_mm",
        "outer_diameter_mm",
    )
    lines += [
        "",
        "  ".join(f"{h:>14}" for h in head3),
        "  ".join(f"{u:>14}" for u in ("", "deg", "deg", "mm", "mm", "mm")),
    ]
    for r in rows:
        lines.append(f"{r['follower']:>14}  " + "  ".join(f"{_fmt(r[k], 2):>14}" for k in keys3))
    # the running machine: wear (the paper's claim, made measurable), life, spring, shaft
    head2 = ("follower", "wear max", "pitting life", "k min", "jump speed", "T drive")
    lines += [
        "",
        "  ".join(f"{h:>14}" for h in head2),
        "  ".join(f"{u:>14}" for u in ("", "um/Mcycle", "cycles", "N/m", "rpm", "N m")),
    ]
    for r in rows:
        life, free = r["pitting_life_cycles"], set(r["unbounded_figures"])
        if "life" in free:  # (the stress has no bound: no life to estimate)
            life_cell = "none"
        else:
            life_cell = _life_text(r["follower"]) if life is None else f"{life:.3g}"
        cells = (
            bounded(r["wear_depth_max_um_per_Mcycle"], 4, "wear", free),
            life_cell,
            _fmt(r["spring_rate_min_N_per_m"], 1),
            "any" if r["jump_speed_rpm"] == 0.0 else _fmt(r["jump_speed_rpm"], 1),
            bounded(r["cam_torque_drive_max_Nm"], 3, "torque", free),
        )
        lines.append(f"{r['follower']:>14}  " + "  ".join(f"{c:>14}" for c in cells))
    return "\n".join(lines + _verdict_lines(rows))


def _verdict_lines(rows: list[dict]) -> list[str]:
    """Each follower's verdict under the tables, and the figures of its that have no
    bound (a designer's review: the verdicts went to stderr only, so a table written
    to a file read as all good, with 2,004,164 MPa beside a cusp unflagged)."""
    lines = ["", f"{'follower':>14}  limits"]
    for r in rows:
        said = "met" if r["valid"] else "BREAKS " + ", ".join(r["breaks"])
        lines.append(f"{r['follower']:>14}  {said}")
        lines += [f"{'':>14}  !! {note}" for note in r["unbounded"]]
    return lines


def _life_text(follower: str, long: bool = False, allowable: float | None = None) -> str:
    """A pitting life of None (no finite estimate) in words: a knife edge has no Hertz
    stress to estimate it from (a line of zero radius: the stress is unbounded,
    contact.contact_stress), any other follower is in the endurance region: its stress
    is below the ``allowable`` [MPa], the endurance stress, itself (the limit check
    multiplies the stress by the safety factor first: a designer's review read
    "within the allowable" beside a broken stress limit)."""
    if follower == FollowerKind.knife_edge:
        return "not estimated (knife edge: no Hertz stress)" if long else "n/a"
    if not long:
        return "endurance"
    at = f" {allowable:g} MPa" if allowable is not None else ""
    return (
        f"endurance (the stress itself is below the allowable{at}; the limit adds the "
        "safety factor)"
    )


def analyze_summary(design: Design) -> dict:
    return summary(analyze(design))
