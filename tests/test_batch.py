"""The batched core (camcore.batch) against the single analysis: for every preset,
follower kind and a spread of geometries (valid and not), each figure it reports equals
the single report's, and its verdict lists the same violations in the same order (less
the profile's own checks, which it does not run)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from test_properties import ci

from camcore import batch, sweep
from camcore.analysis import analyze
from camcore.model import DesignError, FollowerKind, load_preset, set_field
from camcore.report import summary

PRESETS = (
    "paper_example",
    "classroom_harmonic",
    "double_index",
    "indexer_345",
    "valve_lift_roller",
)
KINDS = [k.value for k in FollowerKind]


def differences(fast, single, path=""):
    """Where the batched summary differs from the single one: the same numbers (to
    1e-15, room for a last bit where a vectorized function rounds by position)."""
    if isinstance(fast, dict):
        out = []
        for k, v in fast.items():
            if k == "violations":
                a = [x["code"] for x in v]
                b = [x["code"] for x in single[k] if x["code"] not in batch.PROFILE_CHECKS]
                out += [] if a == b else [(path + k, a, b)]
            elif k == "valid":  # the batch does not run the profile's own checks
                rest = [x for x in single["violations"] if x["code"] not in batch.PROFILE_CHECKS]
                out += [] if v == (not rest) else [(path + k, v, single[k])]
            elif k != "profile_checked":
                out += differences(v, single[k], f"{path}{k}.")
        return out
    if isinstance(fast, list):
        if not isinstance(single, list) or len(fast) != len(single):
            return [(path, fast, single)]
        return [d for a, b in zip(fast, single, strict=True) for d in differences(a, b, path)]
    if isinstance(fast, float) and isinstance(single, int | float):
        same = fast == single or math.isclose(fast, single, rel_tol=1e-15, abs_tol=0.0)
        return [] if same else [(path, fast, single)]
    return [] if fast == single else [(path, fast, single)]


# whole-group changes that break the other limits: follower jump, a self-locking guide,
# a roller that undercuts, a concave face as curved as the cam, the elastic train
VARIANTS = {
    "as_is": {},
    "fast": {"cam.speed_rpm": 4000.0},
    "sticky": {"dynamics.guide_friction": 0.9, "dynamics.overhang_mm": 80.0},
    "big_radii": {"follower.roller_radius_mm": 80.0, "follower.face_radius_mm": -110.0},
    "elastic": {"dynamics.train_stiffness_N_per_m": 5e4, "cam.speed_rpm": 3000.0},
    # a process load toward the cam (beyond the paper), and one pulling it off
    "pushed": {"dynamics.external_load_N": 120.0, "dynamics.train_stiffness_N_per_m": 5e4},
    "pulled": {"dynamics.external_load_N": -60.0, "cam.speed_rpm": 1200.0},
    # the velocity drops instantly at the rise's end: no spring holds the follower
    "velocity_drop": {"motion.segments.0.law": "constant_velocity"},
    # a jump-speed margin the paper's example misses (1.55 x), alone and after the
    # elastic train's jump (the order of checks.run_all)
    "margin": {"limits.min_jump_speed_ratio": 1.6},
    "margin_elastic": {
        "limits.min_jump_speed_ratio": 1.2,
        "dynamics.train_stiffness_N_per_m": 5e4,
        "cam.speed_rpm": 3000.0,
    },
}


def designs_of(preset: str, kind: str, variant: str = "as_is") -> list:
    base = json.loads(load_preset(preset).model_dump_json())
    for path, value in VARIANTS[variant].items():
        set_field(base, path, value, "")
    r_b = base["cam"]["base_radius_mm"]
    points = [
        {"follower.kind": kind, "cam.base_radius_mm": r, "follower.single_offset_mm": s}
        for r in (0.125 * r_b, 0.35 * r_b, 0.7 * r_b, r_b, 1.3 * r_b)
        for s in (0.0, 0.1 * r_b)
    ]
    out = []
    for p in points:
        try:
            out.append(sweep.design_at(base, p))
        except DesignError:
            pass
    return out


def _cases():
    yield from ((p, k, "as_is") for p in PRESETS for k in KINDS)
    yield from (("paper_example", k, v) for v in VARIANTS if v != "as_is" for k in KINDS)


@pytest.mark.parametrize(("preset", "kind", "variant"), list(_cases()))
def test_batch_equals_single_reports(preset, kind, variant):
    designs = designs_of(preset, kind, variant)
    if not designs:
        pytest.skip("no valid input for this follower")
    groups: dict[int, list] = {}
    for d in designs:  # one face or two (e = 0) cannot share a batch
        groups.setdefault(len(analyze(d, verify=False).geo.faces), []).append(d)
    for group in groups.values():
        for d, fast in zip(group, batch.summaries(group), strict=True):
            single = summary(analyze(d, verify=False))
            assert fast["profile_checked"] is False
            assert differences(fast, single) == [], (d.cam.base_radius_mm, kind)
            assert set(single) - set(fast) == set(batch.LEFT_OUT)  # what the README lists


def test_the_spread_has_broken_limits_too():
    """The geometries above are not all valid: the comparison covers verdicts."""
    codes = set()
    for preset, kind, variant in _cases():
        for d in designs_of(preset, kind, variant):
            codes |= {v["code"] for v in batch.summaries([d])[0]["violations"]}
    assert codes >= {
        "pressure_angle",
        "curvature_convex",
        "curvature_face",
        "roller_undercut",
        "contact_stress",
        "high_dwell_arc",
        "jump",
        "guide_jam",
        "contact_lost",
        "dynamic_jump",
        "jump_speed",
    }


def test_fast_rows_equal_rows_and_fall_back_where_they_must():
    """A chunk of mixed followers, an invalid combination and a sliding face with contact
    friction (not batchable: the full analysis, profile_checked = True)."""
    base = json.loads(load_preset("paper_example").model_dump_json())
    points = [
        {"cam.base_radius_mm": r, "follower.kind": k}
        for r in (30.0, 80.0, 95.0)
        for k in ("double_concave", "single_roller")
    ] + [{"cam.base_radius_mm": 80.0, "follower.kind": "no such kind"}]
    fast = sweep.fast_rows(base, points)
    for p, f in zip(points, fast, strict=True):
        full = sweep.row(base, p, verify=False)
        assert f["error"] == full["error"]
        if full["error"] is None:
            codes = [v["code"] for v in json.loads(full["violations"])]
            codes = [c for c in codes if c not in batch.PROFILE_CHECKS]
            assert [v["code"] for v in json.loads(f["violations"])] == codes
            assert f["valid"] == (not codes)
        for k, v in f.items():
            if k in ("violations", "profile_checked", "valid"):
                continue
            w = full[k]
            assert (
                v == w
                or (isinstance(v, float) and math.isclose(v, w, rel_tol=1e-15))
                or (isinstance(v, str) and json.loads(v) == pytest.approx(json.loads(w), rel=1e-15))
            ), k
    friction = dict(base, dynamics={**base["dynamics"], "contact_friction": 0.1})
    bored = dict(base, cam={**base["cam"], "bore_diameter_mm": 30.0})
    envelope = dict(base, limits={**base["limits"], "max_outer_diameter_mm": 150.0})
    for full_only in (friction, bored, envelope):  # (the profile's limits decide too)
        (r,) = sweep.fast_rows(full_only, [{"cam.base_radius_mm": 80.0}])
        assert r["profile_checked"] is True and "profile.vertices" in r
        assert r == {
            **sweep.row(full_only, {"cam.base_radius_mm": 80.0}, verify=False),
            "profile_checked": True,
        }
    (r,) = sweep.fast_rows(envelope, [{"cam.base_radius_mm": 80.0}])
    assert r["valid"] is False and "outer_diameter" in r["violations"]


def test_batch_is_faster_than_one_analysis_each():
    """Not a timing test (bench/ measures it): the batch evaluates the closed forms for
    all designs in one call, so the number of evaluations does not grow with B."""
    designs = designs_of("paper_example", "double_concave")[2:]
    calls = []
    real = batch.local
    try:
        batch.local = lambda *a: calls.append(1) or real(*a)  # type: ignore[assignment]
        batch.summaries(designs * 4)
    finally:
        batch.local = real  # type: ignore[assignment]
    assert len(calls) == 1 + 3  # the grid, and one per zoom round (extremes.ROUNDS)


@st.composite
def geometric_variants(draw) -> tuple[dict, list[dict]]:
    """A preset with any follower and resolution, and three geometries of it (the
    fields a batch varies), drawn over wide ranges: valid or not, limits broken or not."""
    base = json.loads(load_preset(draw(st.sampled_from(PRESETS))).model_dump_json())
    base["follower"]["kind"] = draw(st.sampled_from(KINDS))
    base["limits"]["resolution_deg"] = draw(st.sampled_from([5.0, 1.0, 0.5, 0.25]))
    base["cam"]["speed_rpm"] *= draw(st.sampled_from([0.5, 1.0, 2.5]))
    geometry = st.fixed_dictionaries(
        {
            "cam.base_radius_mm": st.floats(5.0, 150.0),
            "follower.offset_mm": st.floats(0.0, 40.0),
            "follower.single_offset_mm": st.floats(-30.0, 30.0),
            "follower.roller_radius_mm": st.floats(1.0, 60.0),
            "follower.face_radius_mm": st.floats(-600.0, -40.0),
        }
    )
    return base, [draw(geometry) for _ in range(3)]


@ci(60)
@given(geometric_variants())
def test_batch_equals_single_on_random_geometries(case):
    """Random geometries of any preset and follower: the batch reports what the single
    analyses report, verdicts included."""
    base, points = case
    designs = []
    for p in points:
        try:
            designs.append(sweep.design_at(base, p))
        except DesignError:
            continue
    groups: dict[int, list] = {}
    for d in designs:
        groups.setdefault(len(analyze(d, verify=False).geo.faces), []).append(d)
    for group in groups.values():
        for d, fast in zip(group, batch.summaries(group), strict=True):
            single = summary(analyze(d, verify=False))
            assert differences(fast, single) == [], d.model_dump_json()


def test_a_batch_refuses_designs_it_cannot_hold():
    """Contact friction on a sliding face, a non-geometric field that differs, and one
    face mixed with two (e = 0): a ValueError, not wrong numbers."""
    base = json.loads(load_preset("paper_example").model_dump_json())
    flat = dict(base, follower={**base["follower"], "kind": "flat_face"})
    rough = dict(flat, dynamics={**flat["dynamics"], "contact_friction": 0.2})
    a = sweep.design_at(base, {})
    with pytest.raises(ValueError, match="contact friction"):
        batch.summaries([sweep.design_at(rough, {})])
    with pytest.raises(ValueError, match="differ only"):
        batch.summaries([a, sweep.design_at(base, {"cam.speed_rpm": 600.0})])
    with pytest.raises(ValueError, match="number of faces"):
        batch.summaries([a, sweep.design_at(base, {"follower.offset_mm": 0.0})])


def test_explore_reads_the_same_map_and_front_from_batched_rows():
    """The Explore tab's figures, map codes and Pareto front are the same whether its
    rows come from the batched core or from one full analysis per design."""
    from camcore.explore import FIGURES, PROFILE_FIGURES, figure_values, pareto

    base = json.loads(load_preset("paper_example").model_dump_json())
    points = [
        {"follower.kind": k, "cam.base_radius_mm": r, "follower.offset_mm": e}
        for k in ("double_concave", "single_roller")
        for r in (15.0, 40.0, 80.0, 100.0)
        for e in (5.0, 25.0)
    ]
    fast = sweep.run_chunk(base, points, verify=False, fast=True)
    full = sweep.run_chunk(base, points, verify=False)
    names = [n for n in FIGURES if n not in PROFILE_FIGURES]  # (they need the profile)
    np.testing.assert_array_equal(figure_values(fast, names), figure_values(full, names))
    assert [sweep.first_violation(r) for r in fast] == [sweep.first_violation(r) for r in full]
    assert any(sweep.first_violation(r) for r in fast)  # the grid breaks limits too
    for pair in (["cam_size", "stress"], ["pressure_angle", "torque"]):
        assert list(pareto(fast, pair)) == list(pareto(full, pair))


def test_fast_rows_hold_plain_python_values():
    """Rows are data for JSON and Parquet: plain floats, ints, strings, booleans or None,
    as the single analysis' rows are (a numpy float slipped into one figure)."""
    from camcore import sweep

    spec = sweep.parse_spec(
        json.dumps(
            {
                "base": {"preset": "paper_example"},
                "grid": {"follower.kind": ["flat_face", "double_concave"]},
            }
        )
    )
    for r in sweep.run_chunk(spec.base, list(spec.points()), fast=True):
        bad = {
            k: type(v) for k, v in r.items() if type(v) not in (float, int, str, bool, type(None))
        }
        assert not bad, bad


def test_the_batched_core_asks_glibc_to_keep_its_freed_memory(monkeypatch):
    """batch.keep_freed_memory (mallopt: blocks up to KEEP_MB from the heap, as much
    freed memory kept) runs once per process, with the batched core, and holds on
    glibc; elsewhere it says False and changes nothing. The app's server turns it off
    (KEEP_FREED: it keeps its own small threshold, app.main._tune_malloc)."""
    import platform

    from app.main import App
    from camcore import batch

    monkeypatch.setattr(batch, "KEEP_FREED", True)
    monkeypatch.setattr(batch, "_kept", [])
    batch.summaries([load_preset("paper_example")])
    assert batch._kept == [platform.libc_ver()[0] == "glibc"]
    assert batch.keep_freed_memory() is batch._kept[0] and len(batch._kept) == 1
    monkeypatch.setattr(batch, "_kept", [])
    app = App(host="127.0.0.1", port=0, processes=0)
    try:
        assert batch.KEEP_FREED is False
        batch.summaries([load_preset("paper_example")])  # (as a sweep without a worker)
        assert batch._kept == []
    finally:
        app.stop()


def test_a_design_exactly_at_a_limit_meets_it():
    """A designer's review: the double rollers' pressure angle at the dwell is
    asin(e / (r_b + r_c)), 30 deg exactly for e = 10, r_b + r_c = 20 mm; round-off made
    it 30.000000000000004 and refused the design ("exceeds ... by 0.00 deg"), so a
    sweep's smallest r_b came out 13 mm, not 12. Both paths now let a figure within
    checks.ROUND_OFF of its limit meet it; a hundredth of a millimetre smaller fails,
    and its message says by how much in figures that are not zero."""
    from camcore import checks

    data = load_preset("paper_example").model_dump(mode="json")
    data["motion"].update(lift_mm=20, rise_deg=120, high_dwell_deg=60, fall_deg=120)
    data["cam"].update(speed_rpm=300, base_radius_mm=12)
    data["follower"].update(kind="double_roller", roller_radius_mm=8, offset_mm=10)
    at, below = sweep.run_chunk(data, [{}, {"cam.base_radius_mm": 11.99}], fast=True)
    assert at["pressure_angle_max_deg.rise"] > 30.0  # (the round-off is there)
    assert at["pressure_angle_max_deg.rise"] <= checks.most(30.0)
    assert at["valid"] and not below["valid"]
    a = analyze(sweep.design_at(data, {}), verify=False)
    assert not checks.run_all(a, None)
    from camcore.report import report_text

    text = report_text(summary(a), a.design)  # at the limit: printed as the limit
    assert "30.00 / 30.00 deg" in text and "30.000000" not in text
    b = analyze(sweep.design_at(data, {"cam.base_radius_mm": 11.9999}), verify=False)
    (v,) = [v for v in checks.run_all(b, None) if v.code == "pressure_angle"]
    excess = math.degrees(math.asin(10 / 19.9999)) - 30  # (at the dwell: sin phi = e / R)
    assert f"by {excess:.2g} deg" in v.message and excess < 0.005, v.message


def test_rows_say_which_figures_have_no_bound():
    """A review read a cusp's 28,672,817 MPa in a sweep's table as a stress: the rows
    (batched and single) name the figures the violations leave without bound, as the
    text reports print "unbounded" for them; a sound design has none."""
    from camcore.report import unbounded_figures

    data = load_preset("paper_example").model_dump(mode="json")
    data["motion"].update(lift_mm=20, rise_deg=120, high_dwell_deg=60, fall_deg=120)
    data["cam"].update(speed_rpm=300)
    points = [
        {"follower.kind": "single_concave", "cam.base_radius_mm": 10.0},  # a cusp
        {"follower.kind": "single_concave", "cam.base_radius_mm": 40.0},
    ]
    cusp, sound = sweep.run_chunk(data, points, fast=True)
    assert json.loads(cusp["unbounded"]) == ["life", "stress", "wear"]  # (a face slides)
    assert json.loads(sound["unbounded"]) == []
    full = sweep.run_chunk(data, points, verify=False)
    assert [r["unbounded"] for r in full] == [cusp["unbounded"], sound["unbounded"]]
    s = summary(analyze(sweep.design_at(data, points[0]), verify=False))
    assert s["contact_stress_max_MPa"]["cycle"] > 1e6
    # the same figures the text's notes name (their reasons: report.UNBOUNDED)
    from camcore.report import UNBOUNDED, unbounded_notes

    notes = unbounded_notes(s)
    assert notes and set(s["unbounded"]) == {f for why, _ in notes for f in UNBOUNDED[why]}
    assert unbounded_figures(s) == set(s["unbounded"])
    # a sliding face's wear grows without bound there too (a review read 20,220 um per
    # million cycles as a figure); a roller has none to grow (its wear is a true 0)
    from camcore.report import unbounded_of

    for code in ("roller_undercut", "velocity_jump", "guide_jam"):
        assert "wear" in unbounded_of([code], "single_concave")
        assert "wear" not in unbounded_of([code], "double_roller")


def test_an_infinite_stress_at_a_cusp_is_reported_not_raised():
    """A differential fuzzer (9,605 chunks of random designs, batched against single):
    a double concave face folding back exactly at a sample (rho = 0: Eq. 42's stress is
    infinite there) made the single analysis raise OverflowError in the message's
    "more than ... times", stopping report and a sweep without --fast; the batch gave
    its row. Now both give the same row, the stress flagged unbounded."""
    base = load_preset("indexer_345").model_dump(mode="json")
    point = {
        "cam.base_radius_mm": 20.817807864386182,
        "follower.face_radius_mm": -130.09589122247496,
        "follower.offset_mm": 0.0,
    }
    design = sweep.design_at(base, point)
    fast = batch.summaries([design])[0]
    single = summary(analyze(design, verify=False))  # (it raised)
    assert differences(fast, single) == []
    (stress,) = [v for v in single["violations"] if v["code"] == "contact_stress"]
    assert stress["message"].startswith("Hertz stress without bound")
    assert "more than a million times the allowable" in stress["message"]
    assert fast["unbounded"] == single["unbounded"] == ["life", "stress", "wear"]
    (row,) = sweep.run_chunk(base, [point], verify=False)  # a sweep without --fast
    assert row["error"] is None and not row["valid"]


def test_the_largest_pressure_angle_is_the_one_the_check_judges():
    """A CLI review: at 5 deg the report's largest rise pressure angle was its samples'
    (9.52803 deg, under a limit of 9.5281) beside the violation of that limit, which
    the search between the samples had found. The figure is the search's too, per
    rise and fall, in the single report and the batched one alike."""
    from camcore.model import Design
    from camcore.motion import RISE

    def design(resolution: float, limit: float = 30.0) -> Design:
        data = load_preset("paper_example").model_dump(mode="json")
        data["limits"].update(resolution_deg=resolution, max_pressure_angle_deg=limit)
        return Design.model_validate(data)

    fine = summary(analyze(design(0.01), verify=False))["pressure_angle_max_deg"]
    a = analyze(design(5.0, fine["rise"] - 1e-4), verify=False)
    on_rise = a.in_contact & (a.segment_code == RISE)
    assert float(np.degrees(np.abs(a.pressure_angle[on_rise]).max())) < fine["rise"] - 1e-4
    assert [v.code for v in a.violations] == ["pressure_angle"]  # the samples pass; not it
    s = summary(a)
    for kind in ("rise", "fall"):
        assert s["pressure_angle_max_deg"][kind] == pytest.approx(fine[kind], abs=1e-6)
    assert batch.summaries([a.design])[0]["pressure_angle_max_deg"] == s["pressure_angle_max_deg"]
