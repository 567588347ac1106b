"""Property tests over the whole design model (issue 4, "hostile and extreme input").

Every design hypothesis can think of, inside and beyond the allowed ranges, must end
in exactly one of two ways:

* a ``pydantic.ValidationError`` (or ``DesignError`` from the JSON loader) whose
  message names the offending field, or
* an :class:`camcore.analysis.Analysis` whose arrays and whose ``summary()`` numbers
  are all finite, with the broken limits listed as violations;

never another exception, a hang, or a silent NaN/inf.

The field bounds are read from the pydantic model itself, so a field the model gains
later is fuzzed without editing this file.

Budgets: the default (CI) run draws a few thousand designs in well under 90 s on two
cores; ``pytest -m slow tests/test_properties.py`` runs the same properties with many
more examples (``CAMCORE_SLOW_EXAMPLES`` scales it).
"""

from __future__ import annotations

import json
import math
import os
import re
import warnings
from dataclasses import fields
from typing import get_args

import numpy as np
import pytest
from annotated_types import Ge, Gt, Le, Lt
from hypothesis import HealthCheck, example, given, note, settings
from hypothesis import strategies as st
from pydantic import BaseModel, ValidationError

from camcore import checks
from camcore.analysis import Analysis, analyze
from camcore.model import (
    ClassicMotion,
    Design,
    DesignError,
    FollowerKind,
    MotionLaw,
    design_from_json,
    format_validation_error,
)
from camcore.report import summary
from camcore.verify import follower_lift

# --- profiles --------------------------------------------------------------------------

_CI = settings(
    deadline=None,  # timing varies with the drawn resolution; hangs are caught below
    derandomize=True,  # CI runs are reproducible; the slow run explores at random
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much],
    print_blob=True,
)
SLOW_FACTOR = int(os.environ.get("CAMCORE_SLOW_EXAMPLES", "10"))


def ci(n: int) -> settings:
    return settings(_CI, max_examples=n)


def slow(n: int) -> settings:
    return settings(_CI, max_examples=n * SLOW_FACTOR, derandomize=False)


# A hang guard, not a speed test (speed is measured in bench/): one analysis takes
# milliseconds, so only a hang or a runaway loop comes near this.
ANALYSIS_SECONDS = 30.0

# --- the model's fields, read from pydantic ---------------------------------------------


def _bounds(info) -> tuple[float | None, bool, float | None, bool]:
    lo = hi = None
    lo_in = hi_in = True
    for m in info.metadata:
        if isinstance(m, Gt):
            lo, lo_in = float(m.gt), False
        elif isinstance(m, Ge):
            lo, lo_in = float(m.ge), True
        elif isinstance(m, Lt):
            hi, hi_in = float(m.lt), False
        elif isinstance(m, Le):
            hi, hi_in = float(m.le), True
    return lo, lo_in, hi, hi_in


PARTS: dict[str, type[BaseModel]] = {
    name: f.annotation
    for name, f in Design.model_fields.items()
    if isinstance(f.annotation, type) and issubclass(f.annotation, BaseModel)
}
# the motion's scalar fields are those of its classic form (a design may give them
# instead of segments); random segment lists are drawn by programs() below
PARTS["motion"] = ClassicMotion
# (part, field) -> FieldInfo for every leaf field of the design
LEAVES = {(p, n): f for p, cls in PARTS.items() for n, f in cls.model_fields.items()}
NUMERIC = sorted(k for k, f in LEAVES.items() if f.annotation is float)
FIELD_NAMES = {n for _, n in LEAVES} | set(Design.model_fields)


def _in_range(lo, lo_in, hi, hi_in) -> st.SearchStrategy[float]:
    """Anywhere in the closed/open interval, with extra weight at both ends and on a
    log scale (tiny and huge values) for positive intervals."""
    inner = st.floats(
        lo, hi, exclude_min=not lo_in, exclude_max=not hi_in, allow_nan=False, allow_infinity=False
    )
    edges = [
        lo if lo_in else math.nextafter(lo, math.inf),
        hi if hi_in else math.nextafter(hi, -math.inf),
    ]
    parts = [inner, st.sampled_from(edges)]
    if lo is not None and lo >= 0 and hi > 0:
        a = max(lo, 1e-300) if lo > 0 else 1e-300
        parts.append(
            st.floats(math.log10(a), math.log10(hi))
            .map(lambda x: 10.0**x)
            .filter(lambda v: (v > lo or (lo_in and v == lo)) and (v < hi or (hi_in and v == hi)))
        )
    return st.one_of(parts)


# --- valid-range designs ----------------------------------------------------------------


def log_uniform(lo: float, hi: float) -> st.SearchStrategy[float]:
    return st.floats(math.log10(lo), math.log10(hi)).map(lambda x: 10.0**x)


def near_one() -> st.SearchStrategy[float]:
    """A fraction in (0, 1), often within 1e-12 .. 1e-2 of 1 ("close to its limit")."""
    return st.one_of(
        st.floats(0.0, 1.0, exclude_max=True),
        st.integers(1, 14).map(lambda k: 1.0 - 10.0**-k),
        st.sampled_from([0.5, 0.999, 0.0]),
    )


@st.composite
def angles(draw) -> tuple[float, float, float]:
    """(rise, high dwell, fall) [deg] with rise + high + fall <= 360, often at the ends:
    dwells of 0 or almost 360 deg, motions of a hair's width."""
    tiny = st.one_of(st.sampled_from([1e-9, 1e-6, 1e-3, 0.01, 0.1]), log_uniform(1e-9, 1.0))
    total = draw(
        st.one_of(
            st.just(360.0),
            st.floats(1e-6, 360.0),
            st.integers(1, 12).map(lambda k: 360.0 - 10.0**-k),
        )
    )
    w = draw(st.lists(st.one_of(st.floats(0.0, 1.0), tiny), min_size=3, max_size=3))
    w[0] = max(w[0], 1e-12)
    w[2] = max(w[2], 1e-12)
    s = sum(w)
    rise, high, fall = (total * x / s for x in w)
    if draw(st.booleans()):  # a zero high dwell, the rest split between rise and fall
        high = 0.0
    # keep each angle in its open interval; the sum may exceed 360 by round-off only
    rise, fall = (min(max(v, 1e-12), math.nextafter(360.0, 0.0)) for v in (rise, fall))
    return rise, min(high, math.nextafter(360.0, 0.0)), fall


def _field(part: str, name: str) -> st.SearchStrategy[float]:
    return _in_range(*_bounds(LEAVES[part, name]))


@st.composite
def design_dicts(draw, resolutions=None) -> dict:
    """A design dict with every field in its own allowed range; the cross-field
    constraints (concave face wraps the cam, offset below |r + r_b|, lift below L(0))
    are met most of the time by drawing dependent fields as fractions of their limit,
    and broken some of the time."""
    data: dict = {p: {} for p in PARTS}
    for part, name in NUMERIC:
        data[part][name] = draw(_field(part, name), label=f"{part}.{name}")
    data["dynamics"]["overhang_shrinks"] = draw(st.booleans())
    kind = draw(st.sampled_from(list(FollowerKind)))
    data["follower"]["kind"] = kind.value
    data["motion"]["rise_law"] = draw(st.sampled_from(list(MotionLaw))).value
    data["motion"]["fall_law"] = draw(st.sampled_from(list(MotionLaw))).value
    rise, high, fall = draw(angles())
    data["motion"].update(rise_deg=rise, high_dwell_deg=high, fall_deg=fall)
    if resolutions is not None:
        data["limits"]["resolution_deg"] = draw(resolutions)

    f, rb = data["follower"], data["cam"]["base_radius_mm"]
    dependent = draw(st.floats(0, 1)) < 0.85
    if dependent:
        if kind.is_concave:  # |r_f| > r_b, up to the model's limit
            f["face_radius_mm"] = max(-rb * (1.0 + draw(log_uniform(1e-9, 1e4))), -1e5)
        r = (
            f["roller_radius_mm"]
            if kind.is_roller
            else f["face_radius_mm"]
            if kind.is_concave
            else 0.0
        )  # flat face: any offset; knife edge: r = 0
        reach = abs(r + rb)
        if kind.is_double:
            f["offset_mm"] = min(1000.0, reach * draw(near_one()))
        elif draw(st.booleans()):  # an offset single follower, up to its limit
            f["single_offset_mm"] = max(-1000.0, min(1000.0, reach * draw(st.floats(-1, 1))))
        else:
            f["single_offset_mm"] = 0.0
        e = f["offset_mm"] if kind.is_double else abs(f["single_offset_mm"])
        if kind.is_concave and reach > e:
            l0 = math.sqrt(reach**2 - e**2)
            data["motion"]["lift_mm"] = min(1000.0, l0 * max(draw(near_one()), 1e-12))
    return data


def validate(data: dict) -> Design | None:
    """The design, or None after checking that the ValidationError names a field."""
    try:
        return Design.model_validate(data)
    except ValidationError as exc:
        assert_names_a_field(exc)
        return None


def assert_names_a_field(exc: ValidationError) -> str:
    msg = format_validation_error(exc)
    assert "\n" not in msg
    for err in exc.errors():
        named = bool(err["loc"]) or any(n in err["msg"] for n in FIELD_NAMES)
        assert named, f"error does not name a field: {err}"
    return msg


# --- what a finished analysis must satisfy ---------------------------------------------


def _numbers(obj, path="summary"):
    """Every number in a JSON-like object, with its path."""
    if isinstance(obj, bool) or obj is None or isinstance(obj, str):
        return
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield from _numbers(v, f"{path}.{k}")
    elif isinstance(obj, list | tuple):
        for i, v in enumerate(obj):
            yield from _numbers(v, f"{path}[{i}]")
    else:
        assert isinstance(obj, int | float), f"{path}: {type(obj).__name__} is not JSON"
        yield path, obj


def _arrays(obj, path="analysis", seen=None):
    """Every numeric array/number reachable from an Analysis (dataclasses recursively)."""
    seen = set() if seen is None else seen
    if id(obj) in seen:
        return
    seen.add(id(obj))
    if isinstance(obj, np.ndarray):
        if obj.dtype.kind in "fiu":
            yield path, obj
    elif isinstance(obj, bool | int | float):
        yield path, np.asarray(float(obj))
    elif isinstance(obj, list | tuple):
        for i, v in enumerate(obj):
            yield from _arrays(v, f"{path}[{i}]", seen)
    elif hasattr(obj, "__dataclass_fields__"):
        for fl in fields(obj):
            yield from _arrays(getattr(obj, fl.name), f"{path}.{fl.name}", seen)


def check_analysis(a: Analysis) -> dict:
    """All numbers finite, summary JSON-clean, violations consistent; returns summary."""
    kind = a.design.follower.kind
    for path, arr in _arrays(a):
        if path.startswith("analysis.design"):
            continue
        if kind is FollowerKind.flat_face and re.fullmatch(
            r"analysis\.geo(\.faces\[\d\])?\.r", path
        ):
            assert np.all(arr == np.inf), path  # the flat face's radius, by definition
            continue
        if kind is FollowerKind.knife_edge and path == "analysis.stress":
            assert np.all(np.isnan(arr)), path  # no Hertz stress for a point contact
            continue
        bad = ~np.isfinite(arr)
        assert not bad.any(), f"{path}: {int(bad.sum())} non-finite values, e.g. {arr[bad][:3]}"
    for v in a.violations:
        assert math.isfinite(v.amount), f"violation {v.code} amount {v.amount}"
    s = summary(a)
    for path, x in _numbers(s):
        assert math.isfinite(x), f"{path} = {x}"
    json.dumps(s, allow_nan=False)  # what the app and `report --json` emit
    codes = {v.code for v in a.violations}
    assert s["valid"] == (not codes)
    limit = a.design.limits.max_pressure_angle_deg
    pa = s["pressure_angle_max_deg"]
    if max(x for x in (pa["rise"], pa["fall"], 0.0) if x is not None) > limit + 1e-9:
        assert "pressure_angle" in codes
    if a.lift_error is not None:
        assert ("geometric_check" in codes) == (a.lift_error > checks.lift_tolerance(a))
    if (a.guide.FN[a.in_contact.any(0)] < 0).any():  # (F_N = 0: contact kept, a load of 0)
        assert "jump" in codes
    return s


def run_analysis(design: Design, verify: bool) -> Analysis:
    import time

    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        a = analyze(design, verify=verify)
    dt = time.perf_counter() - t0
    note(f"analysis {dt * 1e3:.1f} ms, warnings: {[str(w.message) for w in caught]}")
    assert dt < ANALYSIS_SECONDS, f"analysis hung for {dt:.1f} s"
    return a


# --- 1. designs inside the allowed ranges ------------------------------------------------

COARSE = st.sampled_from([5.0, 2.0, 1.0, 0.5])
ANY_RESOLUTION = st.one_of(COARSE, st.sampled_from([0.1, 0.25]))


def prop_valid_range(data: dict, verify: bool) -> None:
    note(json.dumps(data))
    design = validate(data)
    if design is None:
        return
    a = run_analysis(design, verify)
    check_analysis(a)
    if verify:  # the pruned geometric check equals the brute-force one exactly
        # (at 97 spread angles: brute force costs angles x vertices, up to 50,000 vertices)
        th = a.theta[:: max(1, a.theta.size // 97)]
        args = (a.profile.points, th, [(f.r, f.x_c) for f in a.geo.faces], a.geo.r_b)
        np.testing.assert_array_equal(follower_lift(*args), follower_lift(*args, prune=False))
    codes = {v.code for v in a.violations}
    worst_phi = a.worst.get("pressure_angle_max")
    steep = worst_phi is not None and worst_phi.value > math.radians(89.0)
    if verify and a.profile.is_star_shaped() and not codes & NOT_TRACED and not steep:
        # a convex, not undercut cam with a dwell arc both faces fit on: the independent
        # check must reproduce S(theta) within the export tolerance, however short the
        # segments and coarse the grid. (Beyond 89 deg of pressure angle the tolerance
        # stops growing with 1 / cos(phi) by design, checks.lift_tolerance: a chord a few
        # nm inside the cam then lowers the follower by more, and the check says so.)
        assert a.lift_error <= checks.lift_tolerance(a), a.lift_error


def prop_verdict_independent_of_resolution(data: dict) -> None:
    """The verdict at the design's (coarse) resolution is the verdict at 0.05 deg: a
    limit broken on the fine grid is broken on the coarse one, and vice versa, except
    for borderline cases (the amount by which it is broken is round-off)."""
    note(json.dumps(data))
    design = validate(data)
    if design is None:
        return
    fine = design.model_copy(
        update={"limits": design.limits.model_copy(update={"resolution_deg": 0.05})}
    )
    a, b = run_analysis(design, False), run_analysis(fine, False)
    amount = {}
    for v in [*a.violations, *b.violations]:
        amount[v.code] = max(amount.get(v.code, 0.0), abs(v.amount))
    differ = {v.code for v in a.violations} ^ {v.code for v in b.violations}
    broken = [{v.code for v in x.violations} & GEOMETRY_DEFECTS for x in (a, b)]
    if broken[0] and broken[1]:
        # both grids find the profile is not a cam (a cusp, a crossing): the figures on
        # it (contact windows, stress, how closely its chords follow it) are not of a
        # real cam and may differ by grid; the geometric verdict must still agree
        differ &= GEOMETRY_DEFECTS - {"export_tolerance"}
    assert all(amount[c] < BORDERLINE for c in differ), (
        [v.message for v in a.violations],
        [v.message for v in b.violations],
    )


BORDERLINE = 1e-3  # deg, mm, N or MPa (each violation's own unit): round-off, not a finding


# Violations that make the synthesized profile not the one the follower rolls on.
GEOMETRY_DEFECTS = {
    "curvature_convex",
    "curvature_face",
    "roller_undercut",
    "high_dwell_arc",
    "contact_lost",
    # a profile that could not be sampled to the tolerance (reported as
    # such) is off the exact cam by its measured chord error, not less
    "export_tolerance",
}
# ... and where the lift check may find more than the export tolerance: a jump in V is
# a corner of the pitch curve, where the cam is an arc of the face around the corner
# that the contact points of the angles either side do not trace (the chord between
# them cuts it: ~0.2 um for a 1 mm roller on a constant-velocity fall)
NOT_TRACED = GEOMETRY_DEFECTS | {"velocity_jump"}


def _changed(data: dict, **parts: dict) -> dict:
    """``data`` with some fields of some parts replaced (for the examples below)."""
    return {k: {**v, **parts.get(k, {})} for k, v in data.items()}


NO_BORE = {"bore_diameter_mm": 0.0, "keyway_depth_mm": 0.0, "keyway_width_mm": 0.0}

# a flat face on a 2 mm base circle with a cusp (kept since a resolution once hid it)
FLAT_CUSP = {
    "motion": {
        "fall_deg": 8.0,
        "high_dwell_deg": 0.0,
        "lift_mm": 10.0,
        "rise_deg": 8.0,
        "rise_law": "cycloidal",
        "fall_law": "cycloidal",
    },
    "follower": {
        "face_radius_mm": -1.0,
        "offset_mm": 0.0,
        "roller_radius_mm": 1.0,
        "single_offset_mm": 0.0,
        "kind": "flat_face",
    },
    "cam": {
        "base_radius_mm": 2.0,
        "bore_diameter_mm": 1.0,
        "cutter_diameter_mm": 1.0,
        "keyway_depth_mm": 1.0,
        "keyway_width_mm": 0.1,
        "speed_rpm": 1.0,
        "width_mm": 1.0,
    },
    "dynamics": {
        "contact_friction": 0.0,
        "damping_ratio": 0.0,
        "gravity_m_s2": 1.0,
        "guide_friction": 0.0,
        "guide_length_mm": 1.0,
        "guide_width_mm": 1.0,
        "mass_g": 494.0,
        "overhang_mm": 0.0,
        "preload_mm": 0.0,
        "speed_fluctuation": 1.0,
        "spring_mass_g": 0.0,
        "spring_rate_N_per_m": 0.0,
        "spring_safety_factor": 1.0,
        "overhang_shrinks": False,
    },
    "material": {"cam_E_GPa": 1.0, "cam_nu": 0.0, "follower_E_GPa": 1.0, "follower_nu": 0.0},
    "wear": {
        "coefficient_mm3_per_N_m": 0.0,
        "pitting_exponent": 2.0,
        "pitting_reference_cycles": 1.0,
    },
    "limits": {
        "contact_stress_safety_factor": 1.0,
        "export_tolerance_mm": 1.0,
        "max_pressure_angle_deg": 1.0,
        "resolution_deg": 5.0,
    },
}
# a flat face on a 0.05 deg rise of 1 m: it crosses itself on both grids, and only its
# chords' stray from the exact (non-)cam differs by grid
FLAT_SPIKE = _changed(
    FLAT_CUSP,
    motion={
        "fall_deg": 54.97251374312844,
        "high_dwell_deg": 54.97251374312844,
        "lift_mm": 1000.0,
        "rise_deg": 0.054972513743128434,
    },
    cam={"base_radius_mm": 421.6965034285823},
    dynamics={"gravity_m_s2": 0.0, "mass_g": 1.0},
)
# a single roller of 1 um on a 0.75 mm cam falling 1 mm in 0.96 deg: a pressure angle
# of 89.4 deg, where the check's tolerance is capped (prop_valid_range)
STEEP_FALL = _changed(
    FLAT_CUSP,
    motion={
        "fall_deg": 0.9574468085106382,
        "lift_mm": 1.0,
        "rise_deg": 359.04255319148933,
    },
    follower={"kind": "single_roller", "roller_radius_mm": 0.001},
    cam={**NO_BORE, "base_radius_mm": 0.75},
    dynamics={"gravity_m_s2": 0.0, "mass_g": 1.0},
    limits={"export_tolerance_mm": 1e-05},
)

# a spring of 1e-297 N/m: the smallest preload, 1e306 m, overflowed in mm to inf in
# the summary (and `report --json` refused to write it)
TINY_SPRING = _changed(
    FLAT_CUSP,
    motion={"fall_deg": 180.0, "lift_mm": 10.0, "rise_deg": 180.0},
    follower={"kind": "single_roller"},
    cam={**NO_BORE, "base_radius_mm": 1.0, "speed_rpm": 99559.0},
    dynamics={"gravity_m_s2": 0.0, "mass_g": 259787.0, "spring_rate_N_per_m": 1e-297},
)
# a constant-velocity fall: corners in the pitch curve (NOT_TRACED)
CV_FALL = _changed(
    FLAT_CUSP,
    motion={"fall_deg": 180.0, "lift_mm": 1.0, "rise_deg": 180.0, "fall_law": "constant_velocity"},
    follower={"kind": "single_roller"},
    cam={**NO_BORE, "base_radius_mm": 11.0},
    dynamics={"gravity_m_s2": 0.0, "mass_g": 1.0},
    limits={"export_tolerance_mm": 1e-05},
)


@ci(1200)
@given(design_dicts(resolutions=ANY_RESOLUTION))
@example(data=TINY_SPRING).via("discovered failure")
def test_designs_in_range_analyse_to_finite_numbers(data):
    prop_valid_range(data, verify=False)


@ci(400)
@given(design_dicts(resolutions=COARSE))
@example(data=STEEP_FALL).via("discovered failure")
@example(data=CV_FALL).via("discovered failure")
def test_designs_in_range_pass_or_fail_the_geometric_check_finitely(data):
    prop_valid_range(data, verify=True)


@ci(40)
@given(design_dicts(resolutions=st.sampled_from([0.01, 0.05])))
def test_fine_resolution_designs(data):
    prop_valid_range(data, verify=False)


@ci(150)
@given(design_dicts(resolutions=COARSE))
@example(data=FLAT_SPIKE).via("discovered failure")
@example(data=FLAT_CUSP).via("discovered failure")
def test_verdict_does_not_depend_on_the_resolution(data):
    prop_verdict_independent_of_resolution(data)


# --- 1b. any motion program ----------------------------------------------------------------


@st.composite
def programs(draw) -> list[dict]:
    """A random program: 2-8 motions with dwells between some of them, random laws,
    lifts that close the cycle, angles that sum to 360 deg."""
    n = draw(st.integers(2, 8))
    lifts = [draw(st.floats(0.5, 20.0)) for _ in range(n - 1)]
    signs = [draw(st.sampled_from([1.0, -1.0])) for _ in range(n - 1)]
    steps = [sg * h for sg, h in zip(signs, lifts, strict=True)]
    steps.append(-sum(steps))  # the last motion closes the cycle
    if abs(steps[-1]) < 0.5:
        steps[-1] = 0.0
    motions = [x for x in steps if x != 0.0]
    if len(motions) < 2:
        motions = [5.0, -5.0]
    laws = st.sampled_from(list(MotionLaw))
    segs = []
    for x in motions:
        segs.append(
            {
                "kind": "rise" if x > 0 else "fall",
                "lift_mm": abs(x),
                "law": draw(laws).value,
                "w": draw(st.floats(0.2, 1.0)),
            }
        )
        if draw(st.booleans()):
            segs.append({"kind": "dwell", "w": draw(st.floats(0.0, 1.0))})
    total = sum(g["w"] for g in segs)
    for g in segs:
        g["angle_deg"] = 360.0 * g.pop("w") / total
    segs[-1]["angle_deg"] += 360.0 - sum(g["angle_deg"] for g in segs)
    return segs


@st.composite
def program_designs(draw) -> dict:
    data = draw(design_dicts(resolutions=COARSE))
    data["motion"] = {"segments": draw(programs())}
    return data


@ci(150)
@given(program_designs())
def test_any_program_analyses_and_verifies(data):
    prop_valid_range(data, verify=True)


# --- 2. hostile values ---------------------------------------------------------------------

NOT_A_NUMBER = st.one_of(
    st.sampled_from(
        [
            math.nan,
            math.inf,
            -math.inf,
            None,
            "",
            "abc",
            "nan",
            "inf",
            "-inf",
            "1e400",
            "15 mm",
            [],
            {},
            [1.0],
            {"value": 1.0},
            b"\x00",
        ]
    ),
    st.text(max_size=20).filter(lambda s: not _parses_as_float(s)),
)


def _parses_as_float(s: str) -> bool:
    try:
        return math.isfinite(float(s))
    except ValueError:
        return False


def beyond(lo, lo_in, hi, hi_in) -> st.SearchStrategy[float]:
    """Numbers just or far outside the interval (and the open end itself)."""
    out = [1e308, -1e308, 1e300, -1e-300]
    if lo is not None:
        out += [math.nextafter(lo, -math.inf), lo - 1.0, lo - abs(lo) * 1e-9 - 1e-300]
        if not lo_in:
            out.append(lo)
    if hi is not None:
        out += [math.nextafter(hi, math.inf), hi + 1.0, hi * 10 + 1]
        if not hi_in:
            out.append(hi)
    return st.sampled_from(out)


def _out_of_range(v, lo, lo_in, hi, hi_in) -> bool:
    return (lo is not None and (v < lo or (v == lo and not lo_in))) or (
        hi is not None and (v > hi or (v == hi and not hi_in))
    )


@st.composite
def hostile(draw) -> tuple[dict, list[tuple[tuple[str, ...], str]]]:
    """A design dict (base: a random valid-range one or the defaults) with 1-3 fields
    replaced by garbage, pushed out of range, deleted, or extra keys added. Returns the
    dict and what was done: [(location, how)]."""
    data = draw(st.one_of(st.just({p: {} for p in PARTS}), design_dicts(COARSE)))
    data["limits"]["resolution_deg"] = draw(COARSE)
    done = []
    for _ in range(draw(st.integers(1, 3))):
        how = draw(st.sampled_from(["nan", "range", "missing", "extra", "part", "enum", "top"]))
        part, name = draw(st.sampled_from(sorted(LEAVES)))
        if how == "enum":
            part, name = draw(
                st.sampled_from(
                    [("follower", "kind"), ("motion", "rise_law"), ("motion", "fall_law")]
                )
            )
        if how != "top" and not isinstance(data.get(part), dict):
            continue  # that part was already deleted or replaced
        if how == "nan":
            data[part][name] = draw(NOT_A_NUMBER)
            if data[part][name] is None and type(None) in get_args(LEAVES[part, name].annotation):
                # null is a value of an optional field (a rigid train, no limit): the
                # slow suite found dynamics.train_stiffness_N_per_m = None counted broken
                done = [(t, h) for t, h in done if t != (part, name)]
                continue
            if LEAVES[part, name].annotation is bool:
                how = "bool"  # pydantic reads "yes", "t", 0, 1, ... as booleans
            # a bool field accepts some strings ("yes") and ints; enum fields reject all
        elif how == "range" and (part, name) in NUMERIC:
            b = _bounds(LEAVES[part, name])
            data[part][name] = draw(beyond(*b))
            if not _out_of_range(data[part][name], *b):
                # a value in range replaced whatever an earlier step broke there (the
                # slow suite found a 'nan' step undone by -1e-300 and still counted)
                done = [(t, h) for t, h in done if t != (part, name)]
                continue
        elif how == "missing":  # every field has a default: this must still analyse
            data[part].pop(name, None)
            gone = [(part, name)]
            if draw(st.booleans()):
                gone.append((draw(st.sampled_from(sorted(PARTS))),))
                data.pop(gone[-1][0], None)
            done = [(t, h) for t, h in done if not any(t[: len(g)] == g for g in gone)]
            continue
        elif how == "extra":
            data[part][draw(st.sampled_from(["x", "lift", "Lift_mm", "__class__", ""]))] = 1
            name = None
        elif how == "part":
            data[part] = draw(st.sampled_from([None, 1.0, "motion", [], math.nan]))
            name = None
        elif how == "enum":
            data[part][name] = draw(st.sampled_from(["", "roller", "CYCLOIDAL", 1, None]))
        else:  # top level: schema version, name, unknown keys
            key, val = draw(
                st.sampled_from(
                    [
                        ("schema_version", 0),
                        ("schema_version", 3),
                        ("schema_version", "1"),
                        ("schema_version", None),
                        ("schema_version", -1),
                        ("schema_version", 1e9),
                        ("name", "x" * 201),
                        ("name", None),
                        ("name", 3),
                        ("version", 1),
                        ("", {}),
                    ]
                )
            )
            data[key] = val
            done.append(((key,), "top"))
            continue
        done.append(((part,) if name is None else (part, name), how))
    return data, done


def prop_hostile(case) -> None:
    data, done = case
    note(repr(data))
    note(repr(done))
    try:
        design = Design.model_validate(data)
    except ValidationError as exc:
        msg = assert_names_a_field(exc)
        locs = {tuple(str(p) for p in e["loc"]) for e in exc.errors()}
        # at least one of the things we broke is reported (pydantic shows up to all
        # errors; the first 8 reach the message)
        assert (
            any(
                any(loc[: len(t)] == t or t[: len(loc)] == loc for loc in locs)
                or any(x in msg for x in t)
                for t, _ in done
            )
            or not done
        ), (msg, done)
        # and the JSON path gives the same one-line DesignError
        try:
            text = json.dumps(data, allow_nan=True, default=repr)
        except (TypeError, ValueError):
            return
        with pytest.raises(DesignError) as info:
            design_from_json(text)
        assert "\n" not in str(info.value) and str(info.value)
        return
    # whatever survived validation (e.g. only missing fields) must analyse cleanly
    assert all(how in ("bool", "range") for _, how in done), (done, design)
    check_analysis(run_analysis(design, verify=design.limits.resolution_deg >= 1.0))


@ci(1200)
@given(hostile())
def test_hostile_values_give_a_field_error_or_a_finite_analysis(case):
    prop_hostile(case)


@ci(1)
@given(st.just(None))
def test_missing_everything_is_the_default_design(_):
    check_analysis(analyze(design_from_json("{}"), verify=False))


# --- 3. follower kinds x laws at the extremes, deterministic ------------------------------


@pytest.mark.parametrize("kind", list(FollowerKind))
@pytest.mark.parametrize("law", list(MotionLaw))
def test_every_kind_and_law_on_a_tiny_and_a_huge_cam(kind, law):
    for rb in (1e-2, 1e4):
        d = Design.model_validate(
            {
                "follower": {
                    "kind": kind.value,
                    "roller_radius_mm": min(rb * 0.5, 1000),
                    "face_radius_mm": -min(rb * 3, 1e5),
                    "offset_mm": min(rb * 0.2, 1000),
                },
                "motion": {
                    "lift_mm": min(rb * 0.3, 1000),
                    "rise_law": law.value,
                    "fall_law": law.value,
                },
                "cam": {"base_radius_mm": rb},
                "limits": {"resolution_deg": 1.0},
            }
        )
        check_analysis(analyze(d, verify=True))


# --- slow variants (pytest -m slow) ------------------------------------------------------


@pytest.mark.slow
@slow(2000)
@given(design_dicts(resolutions=ANY_RESOLUTION))
def test_slow_designs_in_range(data):
    prop_valid_range(data, verify=False)


@pytest.mark.slow
@slow(500)
@given(design_dicts(resolutions=COARSE))
def test_slow_designs_in_range_verified(data):
    prop_valid_range(data, verify=True)


@pytest.mark.slow
@slow(2000)
@given(hostile())
def test_slow_hostile(case):
    prop_hostile(case)


@pytest.mark.slow
@slow(20)
@given(design_dicts(resolutions=st.sampled_from([0.01])))
def test_slow_finest_resolution(data):
    prop_valid_range(data, verify=False)


def test_field_table_is_complete():
    """The introspection found every part and numeric field (guards the fuzzing)."""
    assert set(PARTS) == {"motion", "follower", "cam", "dynamics", "material", "wear", "limits"}
    assert len(NUMERIC) >= 24
