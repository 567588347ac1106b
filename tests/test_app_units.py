"""The app's pure parts, without a server: the words it shows (app.panels), the
program table's row actions (app.segments), the controls' design rebuild
(app.controls) and the background loops (app.ticker)."""

from __future__ import annotations

import math
import threading
import time

import numpy as np
import pytest
from conftest import wait_for

from app import controls, panels, scene
from app.segments import Row, moved
from app.ticker import Debouncer, Ticker


def test_nearest_index_rounds_to_the_closest_sample_and_wraps():
    th = np.radians(np.arange(0.0, 360.0, 0.5))
    assert panels.nearest_index(th, 107.4) == 215  # 107.5 is nearer than 107.0
    assert panels.nearest_index(th, 107.2) == 214
    assert panels.nearest_index(th, 360.0 + 1.0) == 2
    assert panels.nearest_index(th, -0.5) == th.size - 1


def test_where_says_station_event_faces_and_segment_boundary(paper_analysis):
    a = paper_analysis
    k = panels.nearest_index(a.theta, math.degrees(a.stations[2]))
    text = panels.where_markdown(a, k, ["e0", "e1", "the second face <b>touches</b>"])
    assert "at station 2" in text and "In contact:" in text
    assert "&lt;b&gt;" in text  # event text escaped (viser renders raw HTML)
    assert "low dwell ends, rise begins" in panels.where_markdown(a, 0, [])

    def seg_at(deg):
        line = panels.where_markdown(a, panels.nearest_index(a.theta, deg), [])
        return line.split(" · ")[1]

    # a boundary is said at its own angle, whichever segment it belongs to, and only there
    assert seg_at(100.0) == "rise ends, high dwell begins"  # (it belongs to the rise)
    assert seg_at(100.1) == "high dwell" and seg_at(169.9) == "high dwell"
    assert seg_at(170.0) == "high dwell ends, fall begins"  # (it belongs to the fall)
    assert seg_at(300.0) == "fall ends, low dwell begins"
    mid = panels.nearest_index(a.theta, 30.0)
    assert "between stations" in panels.where_markdown(a, mid, [])


def test_the_line_under_the_slider_keeps_its_room(paper_analysis):
    """The block under the angle slider keeps the same room whether at a station (its
    words shown) or between two, and whatever its lines' lengths (the panel below had
    jumped up to 30 px during play)."""
    a = paper_analysis
    room = f"<div class='cam-where' style='min-height:{panels.WHERE_LINES * 1.35:.2f}em'>"
    at = panels.where_markdown(a, 0, ["the low dwell ends"])
    between = panels.where_markdown(a, panels.nearest_index(a.theta, 30.0), ["x"])
    assert at.startswith(room) and between.startswith(room)
    assert at.endswith("<br><i>the low dwell ends</i></div>") and "<i>" not in between
    wide = panels.where_markdown(a, 0, [], room_lines=panels.WIDE_WHERE_LINES)
    assert wide.startswith(
        f"<div class='cam-where' style='min-height:{panels.WIDE_WHERE_LINES * 1.35:.2f}em'>"
    )


def test_at_a_station_a_face_that_leaves_is_said_to(paper_analysis):
    """At stations 0 and 3 one face still touches and leaves: the line said both touch
    while the stations diagram drew the leaving one idle. Between stations, and where a
    face arrives (station 2), no face is marked."""
    from camcore.report import summary

    a = paper_analysis
    stations = summary(a)["stations"]
    events, after = [s["event"] for s in stations], [s["contacts"] for s in stations]

    def contact_line(deg: float) -> str:
        k = panels.nearest_index(a.theta, deg)
        return panels.where_markdown(a, k, events, after).split("In contact: ")[1]

    st = np.degrees(a.stations)
    assert contact_line(st[0]).startswith("<b>S1 (left face), S2 (right face) leaving the cam</b>")
    assert contact_line(st[3]).startswith("<b>S1 (left face) leaving the cam, S2 (right face)</b>")
    assert contact_line(st[2]).startswith("<b>S1 (left face), S2 (right face)</b>")
    assert "leaving" not in contact_line(30.0) + contact_line(135.0)


def test_status_panel_states():
    ok = panels.status_html(None, [], 1e-7, True)
    assert "All design limits met" in ok and "0.0001 mm" in ok
    assert "running" in panels.status_html(None, [], None, False)
    bad = panels.status_html("cam.base_radius_mm: <script>", [], None, False)
    assert "Invalid input" in bad and "<script>" not in bad and "All design" not in bad
    # the field as the panel labels it, its path beside it; the path alone otherwise
    assert "<b>Base radius r_b [mm]</b> <code>cam.base_radius_mm</code>" in bad
    # a real refusal, with the value it quotes: the field still named as its control
    from camcore.model import DesignError, design_from_json

    with pytest.raises(DesignError) as err:
        design_from_json('{"cam": {"base_radius_mm": -5, "width_mm": "wide; x: y"}}')
    real = panels.status_html(str(err.value), [], None, False)
    assert "<b>Base radius r_b [mm]</b> <code>cam.base_radius_mm</code>: " in real
    assert "(got -5)" in real and "wide" not in real  # (a string with ';' is not quoted)
    with pytest.raises(DesignError) as err:  # a quoted word stays as the user wrote it
        design_from_json(
            '{"follower": {"kind": "offset_mm"}, "cam": {"width_mm": %s}}' % ("9" * 50)
        )
    real = panels.status_html(str(err.value), [], None, False)
    assert '(got "offset_mm")' in real.replace("&quot;", '"') and "(got 1e+50)" in real
    odd = panels.status_html("<i>x</i>.y: no", [], None, False)
    assert "<code>&lt;i&gt;x&lt;/i&gt;.y</code>: no" in odd
    assert "No solid" in panels.status_html(None, [], None, True, "self-intersecting")
    # a file that could not be opened: said above the design's own (unchanged) state,
    # with no refusal of downloads
    f = panels.status_html(None, [], 1e-7, True, file_error="file <b>x</b>.json: not JSON")
    assert "Could not open" in f and "All design limits met" in f
    assert "<b>x</b>" not in f and "refused" not in f


def test_segment_sums_flag_a_program_that_does_not_close():
    good = [
        {"kind": "rise", "angle_deg": 180, "lift_mm": 5},
        {"kind": "fall", "angle_deg": 180, "lift_mm": 5},
    ]
    assert "⚠" not in panels.segment_sums_markdown(good)
    assert "**340°**" in panels.segment_sums_markdown([dict(good[0], angle_deg=160), good[1]])
    assert "**1 mm**" in panels.segment_sums_markdown([dict(good[0], lift_mm=6), good[1]])


def test_file_stem_names_design_and_follower(paper):
    stem = panels.file_stem(paper)
    assert stem.startswith("chuang_hsu_chang") and "-double_concave-" in stem
    assert panels.file_stem(paper.model_copy(update={"name": "x"})) != stem
    assert panels.slug("../../etc/passwd") == "etc_passwd"


def test_row_actions():
    segs = [{"kind": k, "angle_deg": 90.0} for k in ("rise", "dwell", "fall", "dwell")]
    assert moved(segs, 0, "↑") is None and moved(segs, 3, "↓") is None
    assert [g["kind"] for g in moved(segs, 2, "↑")] == ["rise", "fall", "dwell", "dwell"]
    assert len(moved(segs, 1, "✕")) == 3 and moved(segs[:1], 0, "✕") is None
    assert moved(segs, 4, "+")[-1] == {"kind": "dwell", "angle_deg": 0.0}
    assert moved(segs, 1, "rm -rf") is None  # a client may send anything
    assert Row.of({"kind": "spin", "law": "x"}) == Row("dwell", 0.0, None, None)
    assert Row("dwell", 5.0, 3.0, "cycloidal").as_dict() == {"kind": "dwell", "angle_deg": 5.0}


def test_controls_rebuild_the_design_or_say_why(paper):
    d, err = controls.try_design(paper, {"motion.lift_mm": 12.0})
    assert err is None and d.motion.lift_mm == 12.0 and d.cam == paper.cam
    d, err = controls.try_design(paper, {"motion.rise_deg": 300.0})
    assert d is None and "360" in err
    assert controls.get_path(paper, "follower.kind") == "double_concave"


def test_a_greyed_out_follower_field_cannot_block_the_design(paper):
    """The box of a field the follower does not use stays editable in the browser: 0
    typed as a concave face's roller radius had made the design invalid. It keeps the
    design's value; on a switch to a follower that uses it, the box counts."""
    assert paper.follower.kind.value == "double_concave"
    d, err = controls.try_design(paper, {"follower.roller_radius_mm": 0.0})
    assert err is None and d == paper
    d, err = controls.try_design(
        paper, {"follower.kind": "single roller", "follower.roller_radius_mm": 0.0}
    )
    assert d is None and "roller_radius_mm" in err
    d, err = controls.try_design(
        paper, {"follower.kind": "single roller", "follower.roller_radius_mm": 12.0}
    )
    assert err is None and d.follower.roller_radius_mm == 12.0
    assert d.follower.face_radius_mm == paper.follower.face_radius_mm


def test_ticker_steps_only_while_running():
    steps: list[tuple[float, int]] = []
    t = Ticker(lambda dt, n: steps.append((dt, n)), fps=100.0).start()
    time.sleep(0.1)
    assert steps == []
    t.run(True)
    assert wait_for(lambda: len(steps) >= 5, 5.0)
    t.run(False)
    time.sleep(0.05)
    n = len(steps)
    time.sleep(0.1)
    assert len(steps) == n and t.ticks == n
    assert [s[1] for s in steps] == list(range(n)) and max(s[0] for s in steps) <= 0.2
    t.close()
    t.thread.join(2.0)
    assert not t.thread.is_alive()


def test_debouncer_runs_once_after_quiet_and_one_at_a_time():
    gate = threading.BoundedSemaphore(1)
    runs, active, most = [], [0], [0]

    def work():
        active[0] += 1
        most[0] = max(most[0], active[0])
        time.sleep(0.05)
        runs.append(time.perf_counter())
        active[0] -= 1

    # (the quiet time is far above the burst's gaps: at 0.1 s a loaded machine's
    # scheduler once stalled a 0.02 s gap past it, and the burst ran twice)
    ds = [Debouncer(work, 0.5, gate).start() for _ in range(3)]
    for _ in range(5):  # a burst: one run, after it
        ds[0].poke()
        time.sleep(0.02)
    assert wait_for(lambda: len(runs) == 1, 5.0)
    time.sleep(0.8)
    assert len(runs) == 1
    for d in ds:
        d.poke()
    assert wait_for(lambda: len(runs) == 4, 5.0) and most[0] == 1
    for d in ds:
        d.close()


def test_a_failing_background_job_does_not_end_the_debouncer():
    """A review: a job that raised ended the debouncer's thread, and the tab's checks
    stayed "running" for good. It is logged; the next poke runs the job again."""
    runs = []

    def work():
        runs.append(1)
        if len(runs) == 1:
            raise RuntimeError("a defect of one job")

    d = Debouncer(work, 0.05, threading.BoundedSemaphore(1)).start()
    d.poke()
    assert wait_for(lambda: len(runs) == 1, 5.0)
    d.poke()
    assert wait_for(lambda: len(runs) == 2, 5.0) and d.thread.is_alive()
    d.close()


def test_analyst_workers_match_in_process_survive_a_killed_worker_and_close(paper):
    """app.analyst: a worker's result equals the in-process one; a worker killed (out
    of memory, by hand) is replaced on the next call; after close nothing starts again
    and the work is done in the caller."""
    import os
    import signal

    from app.analyst import Analyst, fast

    an = Analyst(processes=True)
    try:
        r = an.fast(paper)
        here = fast(paper)
        assert r.summary == here.summary
        assert np.array_equal(r.analysis.prog.S, here.analysis.prog.S)
        (pid,) = an._pools["fg"]._processes  # the one foreground worker
        os.kill(pid, signal.SIGKILL)
        assert an.fast(paper).summary == here.summary  # served by a new worker
        assert pid not in an._pools["fg"]._processes
    finally:
        an.close()
    assert an.fast(paper).summary == here.summary  # closed: computed here
    assert an._pools == {"fg": None, "bg": None, "doc": None}


def test_low_dwell_is_the_designs_or_what_the_typed_values_imply(paper):
    assert "**60°**" in panels.low_dwell_text({}, paper)  # 360 - 100 - 70 - 130 (Sec. 6)
    typed = {"motion.rise_deg": 200.0, "motion.high_dwell_deg": 100.0, "motion.fall_deg": 90.0}
    assert "**-30°**" in panels.low_dwell_text(typed) and "negative" in panels.low_dwell_text(typed)
    assert panels.low_dwell_text({}) == "Low dwell β_l: -"


def test_concave_pad_mesh_is_closed_and_outward_either_way_round():
    from app.scene import _sector

    for a0, a1 in ((-0.1, 0.05), (0.3, -0.2)):
        m = _sector(0.01, -0.2, 0.25, 0.256, a0, a1, -0.0075, 0.0075)
        assert m.is_watertight and m.is_winding_consistent
        # outward: the signed volume is the ring sector's, 0.5 (R^2 - r^2) |a1 - a0| w
        expect = 0.5 * (0.256**2 - 0.25**2) * abs(a1 - a0) * 0.015
        assert m.volume == pytest.approx(expect, rel=1e-3)


def test_key_numbers_typeset_units_as_the_curves_do(paper_analysis):
    """The text report's ASCII units (um, N m, kg m2) read as the curves write them."""
    from camcore.report import summary

    text = panels.summary_markdown(summary(paper_analysis))
    assert "µm per million" in text and "N·m" in text and "kg·m²" in text
    assert " um " not in text and " N m " not in text
    assert "Hub wall" not in text  # no bore, no hub wall
    profile = {"area_mm2": 1.0, "hub_wall_mm": 4.25, "outer_diameter_mm": 189.944}
    bored = {**summary(paper_analysis), "profile": profile}
    assert "| Hub wall (thinnest, bore to profile) | 4.25 mm |" in panels.summary_markdown(bored)
    assert "| Outer diameter (stock) | 189.94 mm |" in panels.summary_markdown(bored)
    # the stress limit in significant figures (an allowable of 1e-300 MPa read "0 MPa")
    assert "| 1000 MPa / 1.25 = 800 MPa |" in text
    tiny = {**summary(paper_analysis), "contact_stress_allowable_MPa": 1e-300}
    assert "| 1e-300 MPa / 1.25 = 8e-301 MPa |" in panels.summary_markdown(tiny)
    odd = {**summary(paper_analysis), "contact_stress_allowable_MPa": 12345.0}
    odd["contact_stress_safety_factor"] = 1.0  # (4 significant figures read 1.234e+04)
    assert "| 12345 MPa / 1 = 12345 MPa |" in panels.summary_markdown(odd)
    assert "/\u00a012345\u00a0MPa" in panels.headline_html(odd)


@pytest.mark.parametrize("preset", ["paper_example", "valve_lift_roller"])
def test_the_front_view_frames_the_whole_mechanism(preset):
    """The Front view's lens sees from below the cam's widest radius to above the
    follower's stem at full lift (a reviewer saw both cut off)."""
    from app.scene import camera_for, follower_parts
    from camcore.analysis import analyze
    from camcore.model import load_preset

    a = analyze(load_preset(preset), verify=False)
    pos, look, fov = camera_for("Front", a, 0)
    half = pos[2] * math.tan(fov / 2)  # half the visible height at the cam's plane
    stem_top = max(m.bounds[1, 1] for m, _ in follower_parts(a).values()) + a.prog.S.max()
    cam_bottom = -np.hypot(*a.profile.points.T).max()
    assert look[1] + half >= stem_top and look[1] - half <= cam_bottom


@pytest.mark.parametrize("view", ["Front", "Contact close-up"])
@pytest.mark.parametrize(
    ("kind", "e_s", "width", "height", "panel"),
    [
        ("double_concave", 0.0, 1280, 720, 384),  # the narrow panel
        ("double_concave", 0.0, 1920, 1080, 1000),  # the wide panel
        ("knife_edge", 25.0, 1280, 720, 384),  # an offset follower
    ],
)
def test_the_mechanism_is_framed_beside_the_panel(view, kind, e_s, width, height, panel):
    """The panel covers the view's right side (30 % at 1280 x 720, 52 % with the wide
    panel at 1920): centred on the whole view, the close-up had the right face S2
    under it, and with the wide panel or an offset follower the contacts out of view.
    The follower and every contact of the cycle (in Front the cam too) lie inside the
    uncovered part."""
    from app.scene import camera_for, follower_parts
    from camcore.analysis import analyze
    from camcore.model import Design, load_preset

    data = load_preset("paper_example").with_kind(kind).model_dump()
    data["follower"]["single_offset_mm"] = e_s
    a = analyze(Design.model_validate(data), verify=False)
    aspect, share = width / height, panel / width
    for deg in (40.0, 130.0, 235.0):
        k = panels.nearest_index(a.theta, deg)
        pos, look, fov = camera_for(view, a, k, (aspect, share))
        half = pos[2] * math.tan(fov / 2) * aspect  # half the visible width at the cam
        left, right = pos[0] - half, pos[0] + half - 2 * share * half  # uncovered part
        assert look[0] == pos[0]
        xs = [m.bounds[:, 0] for name, (m, _) in follower_parts(a).items() if name != "guide"]
        xs.append(np.sort(a.point_world[..., 0][a.in_contact])[[0, -1]])
        if view == "Front":
            xs.append(np.array([-1.0, 1.0]) * np.hypot(*a.profile.points.T).max())
        assert left < min(x[0] for x in xs) and max(x[1] for x in xs) < right, (deg, kind)


def test_where_names_the_segments_around_an_empty_dwell():
    """A fall straight into a rise meets it through an empty dwell (motion.segments):
    the line says 'fall ends, rise begins', not the empty dwell's name."""
    from camcore.analysis import analyze
    from camcore.model import Design, load_preset

    data = load_preset("paper_example").with_kind("single_roller").model_dump()
    data["motion"] = {
        "segments": [
            {"kind": "rise", "lift_mm": 15, "law": "cycloidal", "angle_deg": 120},
            {"kind": "dwell", "angle_deg": 60},
            {"kind": "fall", "lift_mm": 15, "law": "cycloidal", "angle_deg": 180},
        ]
    }
    a = analyze(Design.model_validate(data), verify=False)
    line = panels.where_markdown(a, 0, []).split(" · ")[1]
    assert line == "fall ends, rise begins"
    k = panels.nearest_index(a.theta, 120.0)
    assert panels.where_markdown(a, k, []).split(" · ")[1] == "rise ends, high dwell begins"


def test_edited_since_speaks_as_the_controls_do():
    """Explore's list of the edits a load would replace: in the controls' units (Archard
    k in 1e-9), and a program edited as segments is named, not listed as None values."""
    from app.explore import edited_since
    from camcore.model import Design, load_preset

    base = load_preset("paper_example")
    data = base.model_dump()
    data["wear"]["coefficient_mm3_per_N_m"] = 2e-9
    assert edited_since(base, Design.model_validate(data), {}) == [
        "Archard k [10⁻⁹ mm³/(N·m)]: 10.0 → 2.0"
    ]
    data = base.model_dump()
    data["motion"] = {
        "segments": [
            {"kind": "rise", "lift_mm": 10, "law": "cycloidal", "angle_deg": 90},
            {"kind": "fall", "lift_mm": 10, "law": "cycloidal", "angle_deg": 90},
            {"kind": "rise", "lift_mm": 10, "law": "cycloidal", "angle_deg": 90},
            {"kind": "fall", "lift_mm": 10, "law": "cycloidal", "angle_deg": 90},
        ]
    }
    edited = Design.model_validate(data)
    assert edited.motion.classic is None  # two cycles: no rise-dwell-fall-dwell sliders
    assert edited_since(base, edited, {}) == ["the program's segments"]
    assert edited_since(base, base, {}) == []


def test_viser_cast_patch_equals_viser_except_float32_plot_data():
    """app.viser_speedups replaces viser's prop cast (hints built once): for every kind
    of prop it must cast as viser 1.1.1 does, except float32 uPlot ``data``, which it
    keeps (half the bytes a tab receives per edit)."""
    import numpy.typing as npt
    from viser import _assignable_props_api as props_api

    from app import viser_speedups

    original = viser_speedups.VISER_CAST
    assert original is not viser_speedups._cast_value_recursive
    assert props_api.AssignablePropsBase._cast_value_recursive in (
        original,
        viser_speedups._cast_value_recursive,  # installed by an App earlier in this run
    )

    class Viser:  # viser's own cast recurses through self
        _cast_value_recursive = original

    f64, f32, u8 = npt.NDArray[np.float64], npt.NDArray[np.float32], npt.NDArray[np.uint8]
    cases = [
        (f64, [1, 2, 3], "position"),
        (f64, np.arange(3, dtype=np.float32), "position"),  # not plot data: cast
        (f32, np.arange(3.0), "vertices"),
        (npt.NDArray[np.float16], np.arange(3.0), "x"),
        (u8, np.array([[0.5, 1.0, 0.0]]), "colors"),
        (u8, np.array([1, 2], np.int64), "faces"),
        (tuple[f64, ...], (np.arange(2.0), np.arange(2)), "data"),
        (tuple[int, ...], (1, 2), "order"),
        (str, "text", "content"),
        (float, 1.5, "value"),
    ]
    for hint, value, name in cases:
        want = Viser()._cast_value_recursive(hint, value, name)
        got = viser_speedups._cast_value_recursive(None, hint, value, name)
        assert type(got) is type(want)
        for g, w in zip(
            got if isinstance(got, tuple) else (got,),
            want if isinstance(want, tuple) else (want,),
            strict=True,
        ):
            assert np.asarray(g).dtype == np.asarray(w).dtype and np.array_equal(g, w)
    plot = (np.arange(3, dtype=np.float32), np.ones(3, np.float32), np.ones(3, np.int8))
    kept = viser_speedups._cast_value_recursive(None, tuple[f64, ...], plot, "data")
    assert all(k is p for k, p in zip(kept, plot, strict=True))
    assert Viser()._cast_value_recursive(tuple[f64, ...], plot, "data")[0].dtype == np.float64
    other = (np.arange(3), np.ones(3, np.uint8))  # any other dtype: viser's float64
    assert all(
        c.dtype == np.float64
        for c in viser_speedups._cast_value_recursive(None, tuple[f64, ...], other, "data")
    )


def test_plot_columns_go_as_float32_and_the_flags_as_int8():
    """The curves as float32, the shading and the vertical lines' spikes (0/1, -1/2)
    as int8 (viser sends arrays uncompressed: a quarter of the bytes; a value between,
    where a spike is interpolated into the shading, is rounded, not cut)."""
    from app import plots

    x, y, shade, mark = np.arange(4.0), np.linspace(0, 1, 4), np.array([0, 0.5, 1, 1]), -np.ones(4)
    got = plots.wire([x, y, shade, mark], flags=2)
    assert [c.dtype for c in got] == [np.float32, np.float32, np.int8, np.int8]
    assert got[2].tolist() == [0, 0, 1, 1] and got[3].tolist() == [-1] * 4
    assert [c.dtype for c in plots.wire([x, y])] == [np.float32, np.float32]


def test_status_panel_says_a_cutter_that_gouges_escaped():
    html = panels.status_html(None, [], 1e-7, True, cutter_note="a <b>190</b> mm cutter")
    assert "⚠ G-code:" in html and "All design limits met" in html
    assert "<b>190</b>" not in html and "&lt;b&gt;190" in html
    assert "Cutter" not in panels.status_html(None, [], 1e-7, True)


def test_zero_aligned_axes_put_their_zeros_on_one_level():
    """Two y axes ranged alone put their zeros at different heights (a teacher read A
    as non-zero in the dwells): each keeps its data and zero is at the same fraction."""
    from app.plots import zero_aligned

    spans = {"v": (-10.0, 20.0), "a": (-30.0, 25.0), "j": (0.0, 5.0)}
    out = zero_aligned(spans)
    fracs = {k: -lo / (hi - lo) for k, (lo, hi) in out.items()}
    assert max(fracs.values()) - min(fracs.values()) < 1e-12
    for k, (lo, hi) in spans.items():  # every curve still inside its axis
        assert out[k][0] <= lo and out[k][1] >= hi
    assert zero_aligned({"v": (-2.0, 0.0), "a": (-1.0, 0.0)}) == {
        "v": (-2.1, 0.0),
        "a": (-1.05, 0.0),
    }
    # one axis all above zero, one all below (a review: the first had lost its span)
    for spans in ({"v": (0.0, 5.0), "a": (-3.0, 0.0)}, {"v": (-1.0, 1.0), "a": (-3.0, 0.0)}):
        out = zero_aligned(spans)
        for k, (lo, hi) in spans.items():
            assert out[k][0] <= lo and out[k][1] >= hi and out[k][1] > out[k][0]


def test_a_failing_animation_step_does_not_stop_the_animation():
    """A review: one step that raised (a client's NaN camera) killed the tab's
    animation thread for good. It is logged and the animation goes on."""
    import time

    from app.ticker import Ticker

    calls = []

    def step(dt, n):
        calls.append(n)
        if n == 1:
            raise ValueError("Camera look_at must be finite")

    t = Ticker(step, fps=200.0).start()
    t.run(True)
    try:
        deadline = time.time() + 5
        while len(calls) < 5 and time.time() < deadline:
            time.sleep(0.01)
        assert t.thread.is_alive() and len(calls) >= 5 and t.failures == 1
    finally:
        t.close()


def test_escaped_text_makes_no_links():
    """A review: a design named 'https://evil.example' became a clickable link (GFM
    autolinks, which backslash escapes do not stop; checked in Chromium: none is made
    with the word joiners esc() inserts). The text reads the same."""
    text = "see https://evil.example, www.evil.example, _www.x.example or a@b.co"
    out = panels.esc(text)
    for linkable in ("://", "www.", "@b"):  # (a second review: '_www.' had made a link)
        assert linkable not in out
    assert out.replace("\u2060", "").replace("\\_", "_") == text


def test_escaped_text_starts_no_block():
    """A review: a name with a line break could start a Markdown heading ("x\\n===") or
    list ("a\\n1. b") in a message. esc() puts it on one line, as the soft break
    Markdown would have shown anyway."""
    from markdown_it import MarkdownIt

    for name in ("x\n===", "a\n1. b", "a\r\n# b", "a\u2028- b", "a\n\n> b"):
        html = MarkdownIt("commonmark").render(f"Opened **{panels.esc(name)}**.")
        assert html.startswith("<p>") and html.count("<p>") == 1, html
        assert not any(tag in html for tag in ("<h", "<ol", "<ul", "<blockquote")), html


def test_a_silent_browser_costs_one_read_timeout_not_one_per_key():
    """The tab's keys are asked all at once, each waiting READ_TIMEOUT_S: a browser that
    never answers costs that once (one after another, four keys had cost 20 s), and a
    busy one answers them together (one after another, the third of six had timed out
    while the browser drew its first frames, and the tab kept nothing from then on)."""
    from types import SimpleNamespace

    from app.storage import KEYS, READ_TIMEOUT_S, BrowserStore

    asked, lock = [], threading.Lock()
    everyone_asked = threading.Barrier(len(KEYS), timeout=5)

    def get_item(key, timeout=None):  # answers only once every key has been asked
        with lock:
            asked.append((key, timeout))
        everyone_asked.wait()
        return {"camdesigner.working": "w", "camdesigner.view": 3}.get(key)

    store = BrowserStore(SimpleNamespace(local_storage=SimpleNamespace(get_item=get_item)))
    got = store.read_all(KEYS)
    assert got == {**dict.fromkeys(KEYS), "camdesigner.working": "w"} and not store.silent
    assert sorted(asked) == sorted((k, READ_TIMEOUT_S) for k in KEYS) and READ_TIMEOUT_S >= 20

    asked.clear()
    timed_out_together = threading.Barrier(len(KEYS), timeout=5)

    def silent(key, timeout=None):  # (asked in turn, the first one's wait would fail and
        with lock:  # the rest would not be asked)
            asked.append(key)
        timed_out_together.wait()
        raise TimeoutError

    store = BrowserStore(SimpleNamespace(local_storage=SimpleNamespace(get_item=silent)))
    assert store.read_all(KEYS) == dict.fromkeys(KEYS) and store.silent
    assert sorted(asked) == sorted(KEYS)  # one wait for all of them
    assert store.read("x") is None and len(asked) == len(KEYS)  # silent: no more asking


def test_headline_figures_are_the_summarys_and_stay_with_the_status(paper_analysis):
    """The figures a designer watches while moving a slider stay in view with the
    status: the summary's largest pressure angle, smallest radius, stress (with its
    limit) and jump speed; what a design does not have is said, not a crash."""
    from camcore.report import summary

    s = summary(paper_analysis)
    html = panels.headline_html(s)
    body = html[html.index("'>") + 2 : html.rindex("</div>")]
    assert " " not in body.replace(" · ", "")  # a line breaks between items only
    line = html.replace("\u00a0", " ")
    pa = max(s["pressure_angle_max_deg"].values())
    rho, jump = s["radius_of_curvature_mm"]["convex_min"], s["jump_speed_rpm"]
    stress = s["contact_stress_max_MPa"]["cycle"]
    limit = s["contact_stress_allowable_MPa"] / s["contact_stress_safety_factor"]
    assert f"φ ≤ {pa:.1f}°" in line and f"ρ ≥ {rho:.1f} mm" in line and "concave" not in line
    assert f"≤ {stress:.1f} / {limit:g} MPa" in line and f"jumps at {jump:.0f} rpm" in line
    assert "/ 800 MPa" in line  # the default grade: 1000 MPa over the factor 1.25
    odd = dict(s, jump_speed_rpm=None, contact_stress_max_MPa={"cycle": None})
    odd["radius_of_curvature_mm"] = {"convex_min": 40.0, "concave_min": 12.34}
    line = panels.headline_html(odd).replace("\u00a0", " ")
    assert "no jump" in line and "concave ≥ 12.3 mm" in line
    assert "σ<sub>H</sub> none: a knife edge" in line  # (an app review: "σH –" said nothing)
    line = panels.headline_html(dict(s, jump_speed_rpm=0.0)).replace("\u00a0", " ")
    assert "jumps at any speed" in line  # (machine.velocity_drop), not "jumps at 0 rpm"
    status = panels.status_html(None, [], 1e-7, True, headline=line)
    assert status.index("cam-headline") < status.index("All design limits met")
    # after an input error the figures are the last valid design's: below the error
    bad = panels.status_html("cam.width_mm: no", [], 1e-7, True, headline=line)
    assert bad.index("Invalid input") < bad.index("cam-headline")


def test_a_jammed_guide_says_its_force_figures_are_unbounded():
    """A review read '8690819489.753 N' and '461062293.8 MPa' as figures: toward a jam
    (self-locking guide) the forces have no bound, and the report, the key numbers and
    the headline say so; a design without a jam says nothing of it."""
    from camcore.analysis import analyze
    from camcore.model import load_preset
    from camcore.report import jam_note, report_text, summary

    d = load_preset("paper_example").with_kind("single_roller")
    data = d.model_dump()
    data["motion"]["segments"][0]["lift_mm"] = data["motion"]["segments"][2]["lift_mm"] = 1000.0
    s = summary(analyze(type(d).model_validate(data), verify=False))
    assert "guide_jam" in {v["code"] for v in s["violations"]}
    note = jam_note(s)
    ((lo, hi),) = next(v["ranges_deg"] for v in s["violations"] if v["code"] == "guide_jam")
    assert note is not None and f"theta = {lo:g}-{hi:g} deg" in note and "without bound" in note
    assert f"  !! {note}" in report_text(s)
    assert f"guide jams (self-locking) at theta = {lo:g}-{hi:g} deg" in panels.summary_markdown(s)
    assert "σ<sub>H</sub> unbounded: the guide jams" in panels.headline_html(s).replace(
        "\u00a0", " "
    )
    # the figures themselves say it (a designer's review read "1540056.45 N" and
    # "18329206986.279 N·m" in the key numbers beside the note)
    text, keys = report_text(s), panels.summary_markdown(s)
    for label in ("max F1 / F2", "shaft torque drive / brake", "power max / mean"):
        assert f"{label}" in text and _row(text, label).endswith("unbounded"), label
    assert "  unbounded / " in _row(text, "max F_N cycle / high dwell")
    assert _row(text, "pitting life").endswith("none to estimate: the contact stress has no bound")
    assert (
        "| Max F1 / F2 | unbounded |" in keys
        and "| Max stress cycle / high dwell | unbounded" in keys
    )
    assert "whole cycle / high dwell (one-face windows included) | unbounded / " in keys
    ok = summary(analyze(load_preset("paper_example"), verify=False))
    assert jam_note(ok) is None and "jams" not in panels.summary_markdown(ok)
    assert "unbounded" not in report_text(ok) + panels.summary_markdown(ok)


def _row(text: str, label: str) -> str:
    """The value of the text report's row ``label``."""
    return next(ln for ln in text.splitlines() if ln.strip().startswith(label)).strip()


def test_a_cusped_cam_says_its_stress_has_no_bound():
    """A teacher's review: r_b = 15 mm folds the paper's cam back and the headline read
    'σH ≤ 1957662.6 / 800 MPa'. Toward a cusp the stress has no bound: said in the
    report, the key numbers and the headline."""
    from camcore.analysis import analyze
    from camcore.model import load_preset
    from camcore.report import cusp_note, report_text, summary

    data = load_preset("paper_example").model_dump()
    data["cam"]["base_radius_mm"] = 15.0
    s = summary(analyze(type(load_preset("paper_example")).model_validate(data), verify=False))
    note = cusp_note(s)
    ranges = [
        r
        for v in s["violations"]
        if v["code"] in ("roller_undercut", "curvature_convex")
        for r in v["ranges_deg"]
    ]
    assert ranges and note is not None
    assert all(f"{lo:g}-{hi:g}" in note or f"{lo:g}" in note for lo, hi in ranges[:4])
    assert f"  !! {note}" in report_text(s) and "cusp or folds back" in panels.summary_markdown(s)
    line = panels.headline_html(s).replace("\u00a0", " ")
    assert "σ<sub>H</sub> unbounded: the cam has a cusp" in line and "MPa" not in line
    assert cusp_note(summary(analyze(load_preset("paper_example"), verify=False))) is None
    # the stress itself says it; the force has a bound (a cusp is no jam)
    text = report_text(s)
    assert "  unbounded / " in _row(text, "max stress cycle / high dwell")
    assert "unbounded" not in _row(text, "max F_N cycle / high dwell")
    assert "| Max stress cycle / high dwell | unbounded / " in panels.summary_markdown(s)


def test_a_velocity_jump_says_its_force_figures_are_unbounded():
    """A review: a constant-velocity rise's force and stress maxima read as bounds,
    although the cam strikes the follower there (an infinite acceleration)."""
    from camcore.analysis import analyze
    from camcore.model import load_preset
    from camcore.report import impulse_note, report_text, summary

    data = load_preset("paper_example").model_dump()
    data["motion"]["segments"][0]["law"] = "constant_velocity"
    s = summary(analyze(type(load_preset("paper_example")).model_validate(data), verify=False))
    md = panels.summary_markdown(s)
    note = impulse_note(s)
    assert note is not None and "theta = 0, 100 deg" in note  # the rise's two ends
    assert (
        f"  !! {note}" in report_text(s)
        and "velocity jumps (an infinite acceleration) at theta = 0, 100 deg" in md
    )
    # every figure linear in the force says so too (a review read "13.914 / 2.391 N"
    # and "1.185 / 1.112 N m" beside F_N's "unbounded"); the flywheel's energy is finite
    text = report_text(s)
    for label in ("max F1 / F2", "shaft torque drive / brake", "power max / mean"):
        assert _row(text, label).endswith("unbounded"), label
    assert "unbounded" not in _row(text, "flywheel energy / inertia")
    assert "unbounded: the velocity jumps" in panels.headline_html(s).replace("\u00a0", " ")


def test_a_full_table_is_a_program_the_browser_keeps():
    """The kept program's size bound holds a full table written with full-precision
    numbers (the Explore setup's 4,096 characters had refused 48 segments)."""
    import json

    from app import storage
    from camcore.model import MAX_SEGMENTS

    seg = {"kind": "rise", "angle_deg": 1 / 3, "lift_mm": 1000 / 7, "law": "modified_trapezoid"}
    text = json.dumps([seg] * MAX_SEGMENTS)
    assert len(text) > 4096 and storage.parse_program(text) == [seg] * MAX_SEGMENTS
    assert storage.parse_program(json.dumps([seg] * (MAX_SEGMENTS + 1))) is None


def test_the_view_tab_says_what_the_colours_mean():
    """A teacher's review: nothing said what the 3D view's colours meant, and the red
    contact balls hid a broken stretch's red. Every colour the scene draws with is in
    the legend, and the contact points are not the broken-limit red."""
    html = scene.legend_html()
    colours = {n: v for n, v in vars(scene).items() if n.endswith("_RGB") and "WEAR" not in n}
    assert len(colours) >= 13
    for name, rgb in colours.items():  # every colour the scene module defines
        assert f"rgb{tuple(rgb)}" in html, name
    for end in (scene.WEAR_LOW_RGB, scene.WEAR_HIGH_RGB):  # the wear band's two ends
        assert f"rgb{tuple(int(x) for x in end)}" in html
    assert "np." not in html
    # per-vertex colours go as linear values (three.js brightens them otherwise: the
    # dwell arcs were drawn pastel beside their swatches)
    assert scene.vertex_colors(np.array([0, 255, 128, 30])).tolist() == [0, 255, 55, 3]
    # no two of them so close that their swatches cannot be told apart
    names = list(colours)
    for i, a in enumerate(names):
        for b in names[i + 1 :]:
            gap = max(abs(x - y) for x, y in zip(colours[a], colours[b], strict=True))
            assert gap > 40, (a, b)


def test_key_numbers_name_a_field_by_its_control():
    """A teacher's review read 'rigid (dynamics.train_stiffness_N_per_m not set)'."""
    from camcore.analysis import analyze
    from camcore.model import load_preset
    from camcore.report import summary

    md = panels.summary_markdown(summary(analyze(load_preset("paper_example"), verify=False)))
    assert "rigid (Train stiffness k₁ not set)" in md and "dynamics.train" not in md


def test_a_gcode_too_long_for_one_file_is_said_before_the_download():
    """A review: the million-move cap of the G-code was found only at the download."""
    from app import analyst
    from camcore import toolpath
    from camcore.analysis import analyze
    from camcore.model import load_preset

    data = load_preset("paper_example").model_dump()
    data["limits"]["export_tolerance_mm"] = 1e-5
    data["cam"]["pass_depth_mm"] = 0.15  # 100 passes of a fine profile
    a = analyze(type(load_preset("paper_example")).model_validate(data), verify=False)
    note = analyst._cutter_gouges(a)
    assert note is not None and "more than 1,000,000 in one file" in note
    with pytest.raises(toolpath.ExportError, match="in one file"):
        toolpath.gcode(a)
    assert analyst._cutter_gouges(analyze(load_preset("paper_example"), verify=False)) is None


def test_the_papers_table_1_stays_for_a_follower_we_cannot_compute():
    """A review: in the transposed Compare table a follower without a result lost the
    paper's own Table 1 figure, which needs no result of ours."""
    from app.compare import table_markdown
    from camcore.analysis import analyze
    from camcore.model import PAPER_FOLLOWERS, load_preset
    from camcore.report import summary

    d = load_preset("paper_example")
    ok = {"summary": summary(analyze(d, verify=False))}
    results = {k: ok for k in PAPER_FOLLOWERS}
    results[PAPER_FOLLOWERS[0]] = "cannot be computed"
    md = table_markdown(results, d)
    row = next(line for line in md.splitlines() if line.startswith("| paper's Table 1"))
    assert "| 133.496 |" in row and "not computable" in md


def test_compare_says_why_the_faces_win_and_its_rows_show_it():
    """A teacher's review: the cycle's σ_H maxima of the single and double concave
    faces differ little (52.4 against 51.9 MPa), and a class read "double does
    nothing". The tab now says why above the table; the paper example's rows bear it
    out: the concave faces' stress is a fraction of the rollers', and in the high
    dwell the double face's is below the single face's (the load shared)."""
    from app.compare import WHY, table_markdown
    from camcore.analysis import compare
    from camcore.model import load_preset
    from camcore.report import summary

    d = load_preset("paper_example")
    results = {k: {"summary": summary(a)} for k, a in compare(d).items()}
    md = table_markdown(results, d)
    assert md.startswith(WHY) and "1/ρ − 1/|r_f|" in WHY
    s = {k.value: r["summary"] for k, r in results.items()}
    cycle = {k: v["contact_stress_max_MPa"]["cycle"] for k, v in s.items()}
    assert cycle["double_concave"] < cycle["double_roller"] / 3
    assert cycle["single_concave"] < cycle["single_roller"] / 3
    dwell = s["double_concave"]["contact_stress_max_MPa"]["high_dwell_two_contact"]
    assert dwell < s["single_concave"]["contact_stress_max_MPa"]["high_dwell"]


def test_history_keeps_one_step_per_burst_and_empties_redo_on_a_change():
    """app.history: changes within SETTLE_S of each other are one step (a slider drag),
    the design before the burst is the one kept; undo and redo swap the design on
    screen between the two sides; a new change empties the redo side; at most MOST
    steps are kept."""
    from app import history
    from camcore.model import Design

    d = [Design(name=f"d{i}") for i in range(5)]
    h = history.History()
    assert h.undo(d[0]) is None and h.text() == ""
    h.record(d[0], 10.0)  # d0 -> d1
    h.record(d[1], 10.2)  # d1 -> d2, the same drag
    h.record(d[2], 11.0)  # d2 -> d3, a step of its own
    assert h.past == [d[0], d[2]]
    assert h.undo(d[3]) == d[2] and h.undo(d[2]) == d[0] and h.undo(d[0]) is None
    assert h.redo(d[0]) == d[2] and h.future == [d[3]]
    assert h.text() == "1 step to undo, 1 to redo"
    h.record(d[2], 11.1)  # a change after an undo: a step of its own, redo emptied
    assert h.past == [d[0], d[2]] and h.future == []
    for i in range(200):
        h.record(Design(name=f"x{i}"), 20.0 + i)
    assert len(h.past) == history.MOST and h.past[-1].name == "x199"
    # a change undone by hand within one burst leaves a step equal to the design on
    # screen: undo skips it rather than seem to do nothing
    h = history.History()
    h.record(d[0], 1.0)  # d0 -> d1
    h.record(d[1], 1.1)  # d1 -> d0 again, the same burst: past [d0], screen d0
    assert h.undo(d[0]) is None and h.past == []


def test_station_lines_are_numbered_above_the_plots():
    """A teacher's review: the dashed station lines carried no numbers. An axis above
    each plot labels them at their angles; coinciding stations share one label, and
    stations too close for two labels side by side get a second row, each number over
    its own line (a later review: "1,2" between the paper's stations 1 and 2 could not
    say which window was which)."""
    from app.plots import STATION_LABEL_DEG, station_axes

    (ax,) = station_axes(np.array([0.0, 100.0, 100.0, 170.0, 170.0, 300.0]))
    assert ax["side"] == 0 and ax["scale"] == "x"
    assert ax["splits"] == [0.0, 100.0, 170.0, 300.0]
    assert ax["values"] == ["0", "1,2", "3,4", "5"]
    # the paper's double faces: 1 and 2 are 7.4 deg apart, 3 and 4 7.4 too
    low, high = station_axes(np.array([0.0, 100.0, 107.4, 162.6, 170.0, 300.0]))
    assert low["values"] == ["0", "1", "3", "5"] and high["values"] == ["2", "4"]
    assert low["splits"] == [0.0, 100.0, 162.6, 300.0] and high["splits"] == [107.4, 170.0]
    assert low["side"] == high["side"] == 0
    for row in (low, high):  # each row's numbers stand apart
        assert np.all(np.diff(row["splits"]) >= STATION_LABEL_DEG)
    # three within the distance: the third joins the upper row's number
    low, high = station_axes(np.array([10.0, 14.0, 18.0]))
    assert low["values"] == ["0"] and high["values"] == ["1,2"]


def test_the_status_says_where_its_violations_are_marked():
    """Red spans mark the cam and the curves; a jump at one cam angle spans none, so the
    status does not promise red there (a teacher's review of a harmonic law)."""
    from types import SimpleNamespace as V

    from app.panels import _where_red

    point, span = V(ranges_deg=((100.0, 100.0),)), V(ranges_deg=((40.0, 60.0),))
    assert _where_red([point, point]) == "at the cam angles listed"
    assert _where_red([span]) == "red on the cam and the curves"
    assert _where_red([span, point]) == "red on the cam and the curves where they span an angle"
    assert _where_red([V(ranges_deg=())]) == "listed below"  # (a hub wall: no angle)


def test_the_compare_table_says_unbounded_maxima_not_their_samples():
    """A designer's review: a follower whose cam has a cusp (or whose velocity jumps)
    showed the samples' largest stress, millions of MPa, as a figure. Such a cell says
    unbounded, with the report's note under the table; a cusp leaves the force bounded."""
    from app.compare import table_markdown
    from camcore.analysis import analyze
    from camcore.model import FollowerKind, load_preset
    from camcore.report import summary

    d = load_preset("paper_example")
    data = d.model_dump()
    data["cam"]["base_radius_mm"] = 15.0  # the cam folds back under the concave faces
    cusped = type(d).model_validate(data)
    data = d.model_dump()
    data["motion"]["segments"][0]["law"] = "constant_velocity"
    jolted = type(d).model_validate(data)
    concave, roller = FollowerKind.double_concave, FollowerKind.single_roller
    results = {
        concave: {"summary": summary(analyze(cusped.with_kind(concave), verify=False))},
        roller: {"summary": summary(analyze(jolted.with_kind(roller), verify=False))},
    }
    md = table_markdown(results, d)
    row = {ln.split(" | ")[0]: ln.rstrip(" |").split(" | ")[1:] for ln in md.splitlines()}
    force, stress = row["| F_N max cycle [N]"], row["| σ_H max cycle [MPa]"]
    assert force[0] != "unbounded²" and float(force[0]) > 0  # a cusp: the force is bounded
    assert stress[0] == "unbounded²"
    assert force[1] == stress[1] == "unbounded²"
    assert f"- ² *{concave.label}*: the profile has a cusp" in md
    assert f"- ² *{roller.label}*: the velocity jumps" in md
    plain = {k: {"summary": summary(analyze(d.with_kind(k), verify=False))} for k in results}
    assert "unbounded" not in table_markdown(plain, d)


def test_the_rho_plot_draws_a_roller_s_limit_at_zero_not_at_r_c():
    """A designer's review: the ρ plot drew a roller's limit at r_c, so a sound cam
    whose ρ is 17 mm under a 30 mm roller looked broken. A roller's rule is on the
    pitch radius ρ + r_c (undercut in (0, r_c]): on the cam's ρ the limit is 0, with
    the undercut band -r_c < ρ <= 0 said in the legend; a concave face keeps |r_f|."""
    from app.plots import curve_specs, rho_limit_label
    from camcore.analysis import analyze
    from camcore.model import Design, load_preset

    data = load_preset("paper_example").with_kind("single_roller").model_dump()
    data["follower"]["roller_radius_mm"], data["cam"]["base_radius_mm"] = 30.0, 25.0
    a = analyze(Design.model_validate(data), verify=False)
    assert a.valid  # (no undercut: the pitch radius stays above r_c everywhere)
    (spec,) = [c for c in curve_specs(a) if c["title"].startswith("Radius of curvature")]
    rho, line = (s["fn"](a) for s in spec["series"][:2])
    touching = a.in_contact.any(axis=0)
    assert 0.0 < rho[touching].min() < 30.0 and np.all(line == 0.0)
    assert spec["series"][1]["label"] == rho_limit_label(a.design)
    assert "undercut for −30 < ρ ≤ 0 mm" in rho_limit_label(a.design)
    paper = load_preset("paper_example")
    assert rho_limit_label(paper) == "|r_f| = 250 mm (limit)"


def test_the_server_restarts_once_without_glibcs_thread_cache(monkeypatch):
    """app.main._reexec_without_tcache: one restart with the tunable; the restarted
    process cleans it for its workers and never restarts again, even when glibc has
    dropped the tunable (a privileged binary: a review's endless loop); a user's own
    tcache setting is kept; a failed exec leaves the environment as it was."""
    import os
    import sys

    from app import main

    if main._MALLOC_TRIM is None or sys.platform != "linux":
        pytest.skip("glibc only")
    calls = []
    monkeypatch.setattr(os, "execv", lambda exe, argv: calls.append((exe, list(argv))))
    for key in ("GLIBC_TUNABLES", main.REEXECED):
        monkeypatch.delenv(key, raising=False)
    monkeypatch.setenv("GLIBC_TUNABLES", "glibc.malloc.arena_max=2")
    main._reexec_without_tcache()
    assert calls == [(sys.executable, list(sys.orig_argv))]  # restarted, arguments kept
    assert os.environ["GLIBC_TUNABLES"] == f"glibc.malloc.arena_max=2:{main.NO_TCACHE}"
    main._reexec_without_tcache()  # as the restarted process: no second restart
    assert len(calls) == 1 and os.environ["GLIBC_TUNABLES"] == "glibc.malloc.arena_max=2"
    assert main.REEXECED not in os.environ  # (the workers get glibc's default)
    monkeypatch.delenv("GLIBC_TUNABLES")
    monkeypatch.setenv(main.REEXECED, "set")  # restarted, the tunable dropped by glibc
    main._reexec_without_tcache()
    assert len(calls) == 1 and "GLIBC_TUNABLES" not in os.environ
    monkeypatch.setenv("GLIBC_TUNABLES", "glibc.malloc.tcache_count=7")  # the user's own
    main._reexec_without_tcache()
    assert len(calls) == 1 and os.environ["GLIBC_TUNABLES"] == "glibc.malloc.tcache_count=7"

    def fails(exe, argv):
        raise OSError("no exec")

    monkeypatch.setattr(os, "execv", fails)
    monkeypatch.delenv("GLIBC_TUNABLES")
    main._reexec_without_tcache()
    assert "GLIBC_TUNABLES" not in os.environ and main.REEXECED not in os.environ


def test_the_status_names_a_limit_by_its_control():
    """A teacher's review: the hub wall's violation said "(limits.min_hub_wall_mm)",
    the design's path, where the panel's control is "Min hub wall [mm]"; the folded
    cam's headline read "ρ ≥ 0.0, concave ≥ 0.0 mm" beside "the profile folds back"."""
    from camcore.analysis import analyze
    from camcore.model import Design, load_preset
    from camcore.report import report_text, summary

    data = load_preset("paper_example").model_dump()
    data["cam"]["bore_diameter_mm"] = 158.0
    a = analyze(Design.model_validate(data), verify=False)
    assert "limits.min_hub_wall_mm" in " ".join(v.message for v in a.violations)  # the CLI's
    box = panels.status_html(None, a.violations, None, False)
    assert "(Min hub wall [mm], Material &amp; limits)" in box
    assert "limits.min_hub_wall_mm" not in box
    data = load_preset("paper_example").model_dump()
    data["cam"]["base_radius_mm"] = 20.0
    s = summary(analyze(Design.model_validate(data), verify=False))
    line = panels.headline_html(s).replace("\u00a0", " ")
    assert "ρ → 0: the profile folds back" in line and "ρ ≥" not in line
    assert "the profile folds back (a cusp)" in panels.summary_markdown(s)
    assert "inflection" not in report_text(s)


def test_a_knife_edge_has_no_contact_half_width():
    """A review: "Contact half-width max 0.0000 mm" beside "σH –" for a knife edge,
    which has no Hertz contact at all: no half-width either, in the summary (so in a
    sweep's rows) and the key numbers."""
    from camcore.analysis import analyze
    from camcore.model import load_preset
    from camcore.report import summary

    s = summary(analyze(load_preset("paper_example").with_kind("knife_edge"), verify=False))
    assert s["contact_half_width_max_mm"] is None
    assert "| Contact half-width max | – |" in panels.summary_markdown(s)
    roller = summary(analyze(load_preset("paper_example").with_kind("single_roller")))
    assert roller["contact_half_width_max_mm"] > 0


def test_an_untrusted_design_that_finds_a_parser_defect_is_refused_not_raised(monkeypatch):
    """What a browser sent or kept is read by storage.open_untrusted: a parser defect
    it finds (an OverflowError had killed the restore thread) is a reason, not a crash."""
    from app import storage

    def defect(text):
        raise OverflowError("int too large to convert to float")

    monkeypatch.setattr(storage, "design_from_json", defect)
    assert storage.open_untrusted("{}") == ("not a design this version can read (OverflowError)")
    assert storage.parse_working("{}") is None
    assert storage.working_error("{}") == storage.open_untrusted("{}")


def test_the_force_curve_shades_where_the_face_is_inside_its_guide():
    """guide_overhang (l1 = l1_0 - S < 0) is a limit of the guide forces' arms: the
    force curve shades it, over the angles where S passes the overhang."""
    from app import plots
    from camcore.analysis import analyze
    from camcore.model import Design, load_preset

    data = load_preset("paper_example").model_dump(mode="json")
    data["dynamics"]["overhang_mm"] = 10.0  # under the 15 mm lift
    a = analyze(Design.model_validate(data), verify=False)
    c = plots.curve_data(a)
    titles = [s["title"] for s in plots.curve_specs(a)]
    forces = titles.index("Contact force F_N and guide forces F1, F2")
    inside = np.interp(c.x, np.degrees(a.theta), a.prog.S * 1e3) > 10.0 + 1e-6
    assert inside.any() and (c.shades[forces][inside] == 1.0).all()
    assert not c.shades[forces][~inside].any()


def test_a_tabs_callbacks_run_in_two_lanes_of_the_shared_pool():
    """A security review: each event of a tab whose lock was held parked one of viser's
    32 pool threads (speed slider, overlay toggles, Save clicks), so one tab froze every
    tab. app.inbound.TabLanes runs at most LANES_PER_TAB of a tab's callbacks at once,
    in order, the rest waiting in the tab's own queue; another tab's run at once, and
    a tab with MAX_QUEUED waiting has its next ones dropped."""
    import threading
    from concurrent.futures import ThreadPoolExecutor
    from types import SimpleNamespace

    from app import inbound

    pool = ThreadPoolExecutor(max_workers=8)
    lanes = inbound.TabLanes(pool)
    gate, order, lock = threading.Event(), [], threading.Lock()
    running, most = [0], [0]

    def held(event, i):
        with lock:
            running[0] += 1
            most[0] = max(most[0], running[0])
            order.append(i)  # (started in the order submitted)
        gate.wait(10)
        with lock:
            running[0] -= 1

    tab1 = SimpleNamespace(client_id=1)
    futures = [lanes.submit(held, tab1, i) for i in range(30)]
    other = lanes.submit(lambda e: "served", SimpleNamespace(client_id=2))
    assert other.result(5) == "served"  # while tab 1's two lanes are blocked
    assert most[0] == inbound.LANES_PER_TAB
    extra = [lanes.submit(held, tab1, 100 + i) for i in range(inbound.MAX_QUEUED)]
    waiting = 30 - inbound.LANES_PER_TAB  # before the extra ones came
    assert sum(f.done() for f in extra) == waiting  # the cap's overflow: dropped
    gate.set()
    for f in futures + extra:
        f.result(10)
    assert most[0] == inbound.LANES_PER_TAB
    assert sorted(order[:2]) == [0, 1] and order[2:30] == list(range(2, 30))  # in turn
    assert len(order) == inbound.LANES_PER_TAB + inbound.MAX_QUEUED
    assert lanes.submit(lambda: "no tab").result(5) == "no tab"
    pool.shutdown()
