"""Motion programs beyond the paper's one (issue 10): any sequence of rises, falls and
dwells, constant velocity and polynomial segments fitted to their neighbours, the
continuity check, generalized stations and dwell arcs. Checked against closed forms
and the independent geometric check."""

from __future__ import annotations

import io
import math

import numpy as np
import pytest
import trimesh
from pydantic import ValidationError

from camcore import checks, export, motion
from camcore.analysis import analyze
from camcore.model import Design, FollowerKind, MotionLaw, load_preset
from camcore.report import summary

PAPER = load_preset("paper_example")


def with_program(segments, kind="double_concave", **limits) -> Design:
    data = PAPER.with_kind(kind).model_dump(mode="json")
    data["motion"] = {"segments": segments}
    data["limits"].update(limits)
    return Design.model_validate(data)


def test_double_indexing_preset_is_analysed_verified_exported():
    d = load_preset("double_index")
    a = analyze(d)
    assert a.valid, [v.message for v in a.violations]
    assert a.lift_error <= checks.lift_tolerance(a)  # the independent check
    # the program repeats every 180 deg
    th = np.linspace(0, math.pi, 500, endpoint=False)
    p0, p1 = motion.program(d, th), motion.program(d, th + math.pi)
    np.testing.assert_allclose(p0.S, p1.S, atol=1e-15)
    # stations: each high dwell [start, end] has its two-contact window from
    # start + 2 psi to end - 2 psi (Eqs. 23-24 at the dwell's own radius)
    psi = a.geo.psi_h
    deg = np.degrees(a.stations)
    for start, end in ((60, 110), (240, 290)):
        for expect in (start, start + math.degrees(2 * psi), end - math.degrees(2 * psi), end):
            assert np.min(np.abs(deg - expect)) < 1e-9, expect
    s = summary(a)
    both = [st for st in s["stations"] if st["contacts"] == ["S1", "S2"]]
    assert len(both) == 4  # two high dwells and two low dwells start two-contact spans
    assert len(s["dwells"]) == 4
    mesh = trimesh.load(io.BytesIO(export.stl_bytes(a)), file_type="stl")
    assert mesh.is_watertight
    assert mesh.volume == pytest.approx(a.profile.area * 1e9 * d.cam.width_mm / 1e3, rel=1e-6)


def test_constant_velocity_with_polynomial_blends():
    """A constant-velocity working stroke (20 mm over 100 deg) entered and left through
    degree-5 polynomials fitted to the neighbours: S, V, A continuous everywhere; the
    blend's ends take the dwell's (0, 0) and the stroke's (V = 20 mm / 100 deg, A = 0)
    exactly; the constant-velocity segment has A = J = 0."""
    segs = [
        {"kind": "dwell", "angle_deg": 30},
        {"kind": "rise", "angle_deg": 40, "lift_mm": 5, "law": "polynomial"},
        {"kind": "rise", "angle_deg": 100, "lift_mm": 20, "law": "constant_velocity"},
        {"kind": "rise", "angle_deg": 40, "lift_mm": 5, "law": "polynomial"},
        {"kind": "dwell", "angle_deg": 30},
        {"kind": "fall", "angle_deg": 120, "lift_mm": 30, "law": "cycloidal"},
    ]
    d = with_program(segs, kind="single_roller")
    g = motion.segments(d)
    assert motion.continuity_jumps(g) == []
    v_cv = 20e-3 / math.radians(100)
    blend_in, cv, blend_out = g[1], g[2], g[3]
    np.testing.assert_allclose(blend_in.ends(), (0.0, 0.0, v_cv, 0.0), atol=1e-15)
    np.testing.assert_allclose(blend_out.ends(), (v_cv, 0.0, 0.0, 0.0), atol=1e-15)
    th = np.linspace(cv.start, cv.end, 50)[1:-1]
    p = motion.program(d, th)
    np.testing.assert_allclose(p.V, v_cv, rtol=1e-12)
    assert np.all(p.A == 0) and np.all(p.J == 0)
    # S at the segment ends: 0, 5, 25, 30 mm (lifts add up), the blends hit them exactly
    ends = motion.program(d, np.array([blend_in.start, cv.start, cv.end, blend_out.end]))
    np.testing.assert_allclose(ends.S * 1e3, [0, 5, 25, 30], atol=1e-12)
    a = analyze(d)
    assert a.valid, [v.message for v in a.violations]
    assert a.lift_error <= checks.lift_tolerance(a)


def test_velocity_jump_is_reported_with_its_angle():
    """Constant velocity straight out of a dwell: V jumps by h / beta (an infinite
    acceleration) at both ends."""
    segs = [
        {"kind": "rise", "angle_deg": 90, "lift_mm": 9, "law": "constant_velocity"},
        {"kind": "dwell", "angle_deg": 90},
        {"kind": "fall", "angle_deg": 90, "lift_mm": 9, "law": "cycloidal"},
        {"kind": "dwell", "angle_deg": 90},
    ]
    a = analyze(with_program(segs, kind="single_roller"), verify=False)
    jumps = [v for v in a.violations if v.code == "velocity_jump"]
    assert sorted(v.ranges_deg[0][0] for v in jumps) == pytest.approx([0.0, 90.0])
    assert all(v.amount == pytest.approx(9 / math.radians(90)) for v in jumps)  # mm/rad


def test_acceleration_jump_can_be_waived():
    segs = [
        {"kind": "rise", "angle_deg": 120, "lift_mm": 10, "law": "simple_harmonic"},
        {"kind": "dwell", "angle_deg": 60},
        {"kind": "fall", "angle_deg": 120, "lift_mm": 10, "law": "simple_harmonic"},
        {"kind": "dwell", "angle_deg": 60},
    ]
    a = analyze(with_program(segs, kind="single_roller"), verify=False)
    jumps = [v for v in a.violations if v.code == "acceleration_jump"]
    # SHM: A = h pi^2 / (2 beta^2) at each end, four ends meet dwells
    peak = 10 * math.pi**2 / (2 * math.radians(120) ** 2)
    assert len(jumps) == 4 and all(v.amount == pytest.approx(peak) for v in jumps)
    b = analyze(
        with_program(segs, kind="single_roller", require_continuous_acceleration=False),
        verify=False,
    )
    assert not {v.code for v in b.violations} & {"acceleration_jump", "velocity_jump"}


def test_rise_straight_into_fall_breaks_eq28_for_double_followers():
    segs = [
        {"kind": "rise", "angle_deg": 120, "lift_mm": 10},
        {"kind": "fall", "angle_deg": 120, "lift_mm": 10},
        {"kind": "dwell", "angle_deg": 120},
    ]
    a = analyze(with_program(segs), verify=False)
    v = {v.code: v for v in a.violations}["high_dwell_arc"]
    assert v.equation == "Eq. 28"
    assert v.amount == pytest.approx(math.degrees(4 * a.geo.psi_h), rel=1e-9)
    single = analyze(with_program(segs, kind="single_roller"), verify=False)
    assert "high_dwell_arc" not in {v.code for v in single.violations}


def test_a_program_starting_with_a_fall_sits_on_the_base_circle_at_its_lowest():
    segs = [
        {"kind": "fall", "angle_deg": 90, "lift_mm": 8},
        {"kind": "dwell", "angle_deg": 90},
        {"kind": "rise", "angle_deg": 90, "lift_mm": 8},
        {"kind": "dwell", "angle_deg": 90},
    ]
    d = with_program(segs, kind="single_roller")
    p = motion.program(d, np.linspace(0, 2 * math.pi, 721, endpoint=False))
    assert p.S.min() == pytest.approx(0.0, abs=1e-15) and p.S[0] == pytest.approx(8e-3)
    a = analyze(d)
    assert a.lift_error <= checks.lift_tolerance(a)


@pytest.mark.parametrize(
    "segments, message",
    [
        (
            [
                {"kind": "rise", "angle_deg": 100, "lift_mm": 5},
                {"kind": "fall", "angle_deg": 100, "lift_mm": 5},
            ],
            "motion.segments: the angles sum to 200",
        ),
        (
            [
                {"kind": "rise", "angle_deg": 180, "lift_mm": 5},
                {"kind": "fall", "angle_deg": 180, "lift_mm": 4},
            ],
            "do not close the cycle",
        ),
        (
            [{"kind": "rise", "angle_deg": 180}, {"kind": "fall", "angle_deg": 180, "lift_mm": 4}],
            "lift_mm",
        ),
        (
            [
                {"kind": "dwell", "angle_deg": 180, "lift_mm": 3},
                {"kind": "dwell", "angle_deg": 180},
            ],
            "a dwell has no lift_mm",
        ),
        ([{"kind": "dwell", "angle_deg": 360}], "at least one rise and one fall"),
        ([{"kind": "spin", "angle_deg": 360}], "kind"),
    ],
)
def test_bad_programs_say_which_field(segments, message):
    from camcore.model import format_validation_error

    with pytest.raises(ValidationError) as info:
        with_program(segments)
    assert message in format_validation_error(info.value)


def test_classic_keys_edit_a_classic_program_only():
    d = Design.model_validate({"motion": {"lift_mm": 12, "rise_deg": 90}})
    assert d.motion.lift_mm == 12 and d.motion.rise_deg == 90
    assert d.motion.classic.high_dwell_deg == 70  # the default program's other values
    data = load_preset("double_index").model_dump(mode="json")
    data["motion"]["lift_mm"] = 12
    with pytest.raises(ValidationError, match="edit motion.segments"):
        Design.model_validate(data)


def test_law_families_name_vdi_2143_tasks():
    assert "R-R" in MotionLaw.cycloidal.family
    assert "G-G" in MotionLaw.constant_velocity.family
    assert "degree 5" in MotionLaw.polynomial.family


def test_station_events_tell_the_papers_story():
    """Sec. 4 / Fig. 4 of the paper in words: S1 alone drives the rise, the second face
    touches the high-dwell arc at station 2 and the load is shared, S1 leaves at station
    3, S2 drives the fall, and both rest on the base circle from station 5."""
    events = [st["event"] for st in summary(analyze(PAPER, verify=False))["stations"]]
    assert "rise begins" in events[0] and "S1 carries the load alone" in events[0]
    assert events[1] == "station 1: the rise ends and the high dwell begins"
    assert events[2] == "station 2: S2 touches; from here the load is shared (Eqs. 36-38)"
    assert events[3] == "station 3: S1 leaves the cam; from here S2 carries the load alone"
    assert events[4] == "station 4: the high dwell ends and the fall begins"
    assert "low dwell begins; S1 touches; from here the load is shared" in events[5]
    single = summary(analyze(PAPER.with_kind("single_roller"), verify=False))["stations"]
    assert "same angle as station 1" in single[2]["event"]


def test_a_dwell_below_the_full_lift_is_not_called_high():
    """A program rising in two steps: its middle dwell is "the dwell at S = 8 mm" in
    the station events and the app's angle line (a review: it was called the high
    dwell), the dwell at the full lift stays the paper's high dwell."""
    from app import panels

    a = analyze(
        with_program(
            [
                _move("rise", 60, 8),
                _dwell(40),
                _move("rise", 60, 7),
                _dwell(50),
                _move("fall", 100, 15),
                _dwell(50),
            ]
        ),
        verify=False,
    )
    words = [motion.segment_word(a.segments, i) for i in range(len(a.segments))]
    assert words[:5] == ["rise", "dwell at S = 8 mm", "rise", "high dwell", "fall"]
    # to the micrometre, as the angle line's S (4 significant figures had made a dwell
    # at 12.345 mm read higher than the high dwell at 12.346 mm)
    M = motion
    steps = (
        M.Segment(M.HIGH, 0.0, 1.0, 12.345e-3, 12.345e-3),
        M.Segment(M.HIGH, 1.0, 2.0, 12.346e-3, 12.346e-3),
    )
    assert [M.segment_word(steps, i) for i in (0, 1)] == ["dwell at S = 12.345 mm", "high dwell"]
    events = [st["event"] for st in summary(a)["stations"]]
    assert events[1] == "station 1: the rise ends and the dwell at S = 8 mm begins"
    assert events[3].startswith("station 3: the dwell at S = 8 mm ends and the rise begins")
    assert events[4] == "station 4: the rise ends and the high dwell begins"
    line = panels.where_markdown(a, panels.nearest_index(a.theta, 80.0), [])
    assert "· dwell at S = 8 mm ·" in line


def test_stations_figure_has_a_panel_per_station():
    """The paper's Fig. 4 for any program: one panel per station, titled with its angle
    and captioned with its event; in the printable report too."""
    from camcore import document

    a = analyze(load_preset("double_index"), verify=False)
    fig = document.stations_figure(a)
    drawn = [ax for ax in fig.axes if ax.axison]
    assert len(drawn) == len(a.stations)
    assert drawn[2].get_title().startswith("station 2: θ = ")
    caption = drawn[2].get_xlabel().split("\n")
    assert caption[0] == summary(a)["stations"][2]["event"].split(": ", 1)[1]
    assert caption[1].startswith("S") and " N, σ_H " in caption[1]  # the loads, below
    assert "Stations (the paper's Fig. 4" in document.html_report(a)


def test_the_stations_say_each_faces_load_before_and_after_the_transition():
    """A teacher's review: the captions give each touching face's F_N and Hertz stress
    just before -> just after the station. The forces are checked by hand: in the high
    dwell F_t = M g + k (h + s_p) (Eqs. 29-30, A = 0), one face of the double follower
    carries F_t / cos psi_h, two share it as F_t / (2 cos psi_h) (Eqs. 36-38, the
    README's 136.509 and 68.397 N), and the stress falls as F_N^(1/2) (Eq. 42, the same
    curvatures on both sides of the station)."""
    from camcore import document

    a = analyze(PAPER, verify=False)
    dyn = PAPER.dynamics
    Ft = dyn.mass_g * 1e-3 * dyn.gravity_m_s2 + dyn.spring_rate_N_per_m * (
        (PAPER.motion.lift_mm + dyn.preload_mm) * 1e-3
    )
    alone, shared = Ft / np.cos(a.geo.psi_h), Ft / (2 * np.cos(a.geo.psi_h))
    st = a.stations[2]
    near = a.local(np.array([st - 1e-7, st + 1e-7]))
    np.testing.assert_allclose(near.FN, [[alone, shared], [0.0, shared]], rtol=1e-9)
    s0, s1 = near.stress[0] * 1e-6
    assert s1 == pytest.approx(s0 / np.sqrt(2), rel=1e-6)
    fig = document.stations_figure(a)
    captions = [ax.get_xlabel().split("\n")[1:] for ax in fig.axes if ax.axison]
    assert captions[1] == [f"S1: F_N {alone:.1f} N, σ_H {s0:.1f} MPa"]  # one face
    assert captions[2] == [
        f"S1: F_N {alone:.1f} → {shared:.1f} N, σ_H {s0:.1f} → {s1:.1f} MPa",
        f"S2: F_N 0.0 → {shared:.1f} N, σ_H 0.0 → {s1:.1f} MPa",
    ]
    # a single roller: F_N = F_t, and Eq. 42 by hand for two cylinders, the cam's
    # radius r_b + h in the dwell against the roller's r_c, both of steel
    single = document.station_loads(
        b := analyze(PAPER.with_kind("single_roller"), verify=False),
        b.local(np.mod(np.concatenate([b.stations - 1e-7, b.stations + 1e-7]), 2 * np.pi)),
    )
    m, w = PAPER.material, PAPER.cam.width_mm * 1e-3
    compliance = (1 - m.cam_nu**2) / (m.cam_E_GPa * 1e9) + (1 - m.follower_nu**2) / (
        m.follower_E_GPa * 1e9
    )
    radii = 1 / ((PAPER.cam.base_radius_mm + PAPER.motion.lift_mm) * 1e-3) + 1 / (
        PAPER.follower.roller_radius_mm * 1e-3
    )
    sigma = np.sqrt(Ft / (np.pi * w) * radii / compliance) * 1e-6  # 212.15 MPa
    assert single[2] == f"F_N {Ft:.1f} N, σ_H {sigma:.1f} MPa"  # no face named, none shared
    # past the jump speed the spring cannot hold the follower: F_N < 0 is said so (a
    # review read "F_N -921 → 170 N" as a load). Simple harmonic rise of h over beta:
    # A = +-pi^2 h / (2 beta^2) at its ends, so F_t = M (g + A w^2) + k (S + s_p) there
    data = load_preset("classroom_harmonic").model_dump(mode="json")
    data["cam"]["speed_rpm"] = 8000
    c = analyze(Design.model_validate(data), verify=False)
    dyn, prog = c.design.dynamics, c.design.motion.classic
    h, beta, omega = prog.lift_mm * 1e-3, np.radians(prog.rise_deg), 8000 * 2 * np.pi / 60
    M, k, s_p = dyn.mass_g * 1e-3, dyn.spring_rate_N_per_m, dyn.preload_mm * 1e-3
    edge = np.pi**2 * h / (2 * beta**2) * omega**2  # |A w^2| at the rise's ends
    low, high = M * dyn.gravity_m_s2 + k * s_p, M * dyn.gravity_m_s2 + k * (h + s_p)
    at = np.mod(np.concatenate([c.stations - 1e-7, c.stations + 1e-7]), 2 * np.pi)
    loads = document.station_loads(c, c.local(at))
    assert loads[0].startswith(f"F_N {low:.1f} → {low + M * edge:.1f} N, σ_H ")
    assert loads[1].startswith(
        f"F_N {high - M * edge:.1f} → {high:.1f} N (< 0: the follower leaves the cam), σ_H 0.0"
    )
    assert high - M * edge < 0 < high


def test_stations_figure_fills_the_faces_touching_at_each_station():
    """A teacher's review: the diagram drew S2 open at station 0 and S1 open at station
    3, where the paper's Fig. 4 (and the app's 3D view) has both faces touching: one
    leaves as the other takes over. Filled = touching at the station (just before or
    just after it): for the paper's program S1 alone at 1 (the rise ends) and S2 alone
    at 4 (the fall begins); both at 0 (S2 leaves), 2 (S2 arrives), 3 (S1 leaves) and 5
    (S1 arrives)."""
    from camcore import document

    fig = document.stations_figure(analyze(PAPER, verify=False))
    filled = []
    for ax in [ax for ax in fig.axes if ax.axison]:
        dots = [ln for ln in ax.lines if ln.get_marker() == "o"]
        filled.append(sum(ln.get_markerfacecolor() != "white" for ln in dots))
        labels = {t.get_text() for t in ax.texts}
        assert labels == {"S1", "S2"}
    assert filled == [2, 1, 2, 2, 1, 2]


@pytest.mark.parametrize("offset_mm", [None, 30.0])
def test_stations_figure_locates_each_crop_on_the_whole_cam(offset_mm):
    """A teacher's review: a crop alone does not show where the cam is in its turn.
    Each panel has an inset with the whole cam turned to the station's angle (its span
    the cam's, not the crop's), its theta = 0 datum (the cam frame's +Y ray) at the
    turned place, and the panel's crop as a box; the inset covers no contact point,
    label, title or caption (for a single concave face set off 30 mm too, whose contact
    lies on the right, away from its stem)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from camcore import document

    d = PAPER
    if offset_mm is not None:
        data = PAPER.with_kind("single_concave").model_dump(mode="json")
        data["follower"]["single_offset_mm"] = offset_mm
        d = Design.model_validate(data)
    a = analyze(d, verify=False)
    fig = document.stations_figure(a, width_in=7.0, cols=2)  # the app's size
    FigureCanvasAgg(fig).draw()
    renderer = fig.canvas.get_renderer()
    P = a.profile.points * 1e3
    panels = [ax for ax in fig.axes if ax.axison]
    assert len(panels) == len(a.stations)
    for ax, th in zip(panels, a.stations, strict=True):
        (inset,) = ax.child_axes
        c, s = math.cos(th), math.sin(th)
        X, Y = c * P[:, 0] + s * P[:, 1], -s * P[:, 0] + c * P[:, 1]
        (cam,) = [p for p in inset.patches if p.get_label() == "cam"]
        xy = cam.get_xy()
        assert np.ptp(xy[:, 0]) == pytest.approx(np.ptp(X), abs=1e-6)
        assert np.ptp(xy[:, 1]) == pytest.approx(np.ptp(Y), abs=1e-6)
        assert np.ptp(xy[:, 0]) > 1.9 * a.geo.r_b * 1e3 > 2 * np.ptp(ax.get_xlim())
        (datum,) = [ln for ln in inset.lines if ln.get_label() == "θ = 0"]
        tip = np.array([datum.get_xdata()[-1], datum.get_ydata()[-1]])
        # the cam frame's +Y ray meets the base circle (the low dwell ends at theta = 0)
        assert tip == pytest.approx(a.geo.r_b * 1e3 * np.array([s, c]), abs=0.1)
        (crop,) = [p for p in inset.patches if p.get_label() == "crop"]
        (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
        assert crop.get_bbox().bounds == pytest.approx((x0, y0, x1 - x0, y1 - y0))
        box = inset.get_window_extent(renderer)
        drawn = [t.get_window_extent(renderer) for t in ax.texts]
        drawn += [ax.title.get_window_extent(renderer), ax.xaxis.label.get_window_extent(renderer)]
        drawn += [ln.get_window_extent(renderer) for ln in ax.lines if ln.get_marker() == "o"]
        assert not any(b.overlaps(box) for b in drawn)


def test_every_fall_into_a_rise_gets_its_empty_dwell():
    """A program that repeats (rise, fall) twice: both fall -> rise boundaries carry the
    empty dwell arc on which a double follower's faces meet (the second was skipped:
    the list grew while it was read), so the contact at 0 and at 180 deg is the same."""
    from camcore import motion
    from camcore.analysis import analyze
    from camcore.model import Design, load_preset

    data = load_preset("paper_example").model_dump()
    cycle = [
        {"kind": "rise", "lift_mm": 10, "law": "cycloidal", "angle_deg": 90},
        {"kind": "fall", "lift_mm": 10, "law": "cycloidal", "angle_deg": 90},
    ]
    data["motion"] = {"segments": cycle * 2}
    d = Design.model_validate(data)
    codes = [g.code for g in motion.segments(d)]
    assert codes == [motion.RISE, motion.FALL, motion.LOW] * 2
    a = analyze(d, verify=False)
    k0, k180 = 0, int(np.argmin(np.abs(a.theta - np.pi)))
    assert abs(a.theta[k180] - np.pi) < 1e-12  # a segment boundary: on the grid
    np.testing.assert_array_equal(a.in_contact[:, k0], a.in_contact[:, k180])


# Programs started elsewhere in their cycle: name -> (the program as first written,
# the same program started elsewhere, the angle [deg] of the first's theta = 0 in it).
_R = {"kind": "rise", "angle_deg": 100, "lift_mm": 15, "law": "cycloidal"}
_F = {"kind": "fall", "angle_deg": 130, "lift_mm": 15, "law": "cycloidal"}


def _dwell(angle: float) -> dict:
    return {"kind": "dwell", "angle_deg": angle}


def _move(kind: str, angle: float, lift: float) -> dict:
    return {"kind": kind, "angle_deg": angle, "lift_mm": lift, "law": "cycloidal"}


_PAPER = [_R, _dwell(70), _F, _dwell(60)]
_TWO_RISES = [
    _move("rise", 60, 6),
    _move("rise", 60, 6),
    _dwell(60),
    _move("fall", 100, 12),
    _dwell(80),
]
ROTATED = {
    "low dwell first": (_PAPER, [_dwell(60), _R, _dwell(70), _F], 60.0),
    "fall first": (_PAPER, [_F, _dwell(60), _R, _dwell(70)], 190.0),
    "high dwell first": (_PAPER, [_dwell(70), _F, _dwell(60), _R], 260.0),
    "low dwell split at 0": (_PAPER, [_dwell(30), _R, _dwell(70), _F, _dwell(30)], 30.0),
    "high dwell split at 0": (_PAPER, [_dwell(35), _F, _dwell(60), _R, _dwell(35)], 225.0),
    # the piece of the high dwell after the rise shorter than 2 psi: the arc is the run's
    "high dwell split 1 deg after the rise": (
        _PAPER,
        [_dwell(69), _F, _dwell(60), _R, _dwell(1)],
        259.0,
    ),
    "two dwells in a row": (_PAPER, [_R, _dwell(3), _dwell(67), _F, _dwell(60)], 0.0),
    # a fall straight into a rise (an empty dwell, an arc of 2 psi) mid-program
    "fall into rise mid-program": (
        [_move("rise", 150, 15), _dwell(60), _move("fall", 150, 15)],
        [_move("fall", 150, 15), _move("rise", 150, 15), _dwell(60)],
        150.0,
    ),
    # two rises meeting at theta = 0 (a profile chord across it)
    "two rises meeting at 0": (_TWO_RISES, [_TWO_RISES[1], *_TWO_RISES[2:], _TWO_RISES[0]], 300.0),
}


@pytest.mark.parametrize("kind", ["double_concave", "double_roller", "single_roller"])
@pytest.mark.parametrize("name", list(ROTATED))
def test_a_program_started_elsewhere_makes_the_same_cam(kind, name):
    """Starting the program elsewhere in its cycle turns the cam, nothing else: the
    stations turn with it (a segment boundary that was none before may add one), every
    per-angle result at the turned angles is the same (which faces touch, S, F_N,
    stress), and the profile passes the geometric check with the same area and
    perimeter. A double follower's profile had crossed itself when the program did
    not end with the low dwell, a split dwell lost one face's contact, a dwell piece
    shorter than 2 psi got its own arc, a fall into a rise mid-program and two rises
    meeting at theta = 0 broke the profile's sampling."""
    from camcore.analysis import stations
    from camcore.profile import geometry

    first, segs, shift_deg = ROTATED[name]
    ref, d = with_program(first, kind), with_program(segs, kind)
    if kind == "single_roller":  # an offset axis: its dwell contacts sit off theta + pi/2
        ref, d = (
            x.model_copy(
                update={"follower": x.follower.model_copy(update={"single_offset_mm": 6.0})}
            )
            for x in (ref, d)
        )
    shift = math.radians(shift_deg)
    turned = np.sort(np.mod(stations(ref, geometry(ref)) + shift + 1e-9, 2 * math.pi) - 1e-9)
    own = stations(d, geometry(d))
    assert np.all(np.min(np.abs(own[:, None] - turned[None, :]), axis=0) < 1e-9)
    boundaries = np.array([g.start for g in motion.segments(d)])
    for t in own:  # a station the first program lacks is a boundary of this one
        if np.min(np.abs(turned - t)) > 1e-9:
            assert np.min(np.abs(boundaries - t)) < 1e-9, math.degrees(t)
    grid = analyze(ref, verify=False).theta
    mid = 0.5 * (grid[:-1] + grid[1:])  # between the first program's stations
    a0 = analyze(ref, verify=False, theta=mid)
    a1 = analyze(d, verify=False, theta=np.mod(mid + shift, 2 * math.pi))
    np.testing.assert_array_equal(a1.in_contact, a0.in_contact)
    np.testing.assert_allclose(a1.prog.S, a0.prog.S, rtol=0, atol=1e-12)
    np.testing.assert_allclose(a1.guide.FN, a0.guide.FN, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(a1.stress, a0.stress, rtol=1e-9, atol=1.0)
    full0, full1 = analyze(ref), analyze(d)
    assert [v.code for v in full1.violations] == [v.code for v in full0.violations]
    assert full1.lift_error <= checks.lift_tolerance(full1)
    assert full1.profile.area == pytest.approx(full0.profile.area, rel=1e-6)
    assert full1.profile.perimeter == pytest.approx(full0.profile.perimeter, rel=1e-6)


def test_dwells_that_close_to_round_off_are_one_dwell():
    """Lifts of 5.0 + 2.1 mm up and 7.1 mm down leave the split low dwell at -0.0 and
    8.7e-19 m: still one rest, so no station where a face would leave and retouch it,
    and both faces carry the dwell as with lifts that close exactly."""
    from camcore.analysis import stations
    from camcore.profile import geometry

    def program(a: float, b: float) -> list[dict]:
        return [
            _dwell(30),
            _move("rise", 60, a),
            _move("rise", 40, b),
            _dwell(70),
            _move("fall", 130, a + b),
            _dwell(30),
        ]

    near, exact = with_program(program(5.0, 2.1)), with_program(program(5.0, 2.0))
    assert [g.S0 for g in motion.segments(near)][::5] != [0.0, 0.0]  # not exactly equal
    st_near = np.degrees(stations(near, geometry(near)))
    st_exact = np.degrees(stations(exact, geometry(exact)))
    assert len(st_near) == len(st_exact)  # 0, the boundaries, the high dwell's two
    a = analyze(near, verify=False)
    low = np.degrees(a.theta) < 30  # the low dwell's first piece: both faces rest
    assert a.in_contact[:, low].all()


@pytest.mark.parametrize("kind", ["knife_edge", "single_roller"])
def test_an_offset_follower_on_a_long_dwell(kind):
    """A 340 deg dwell under a follower offset 20 mm: the dwell's contacts sit beside
    theta + pi/2, and ordering them by polar angle from the arc's middle put the last
    first (a self-crossing profile); by the contact's direction it is one arc."""
    d = with_program([_move("rise", 10, 2), _move("fall", 10, 2), _dwell(340)], kind).model_copy(
        update={"cam": PAPER.cam.model_copy(update={"speed_rpm": 100.0})}
    )
    d = d.model_copy(update={"follower": d.follower.model_copy(update={"single_offset_mm": 20.0})})
    a = analyze(d)
    assert a.profile.is_star_shaped() and a.valid, [v.message for v in a.violations]
    assert a.lift_error <= checks.lift_tolerance(a)


def test_eq_28_holds_for_a_run_of_dwells():
    """Two 5 deg dwells in a row between the rise and the fall are one 10 deg dwell:
    Eq. 28 (beta >= 4 psi) refuses them as it refuses the one dwell, by as much."""

    def short(program):
        (v,) = [
            v
            for v in analyze(with_program(program), verify=False).violations
            if v.code == "high_dwell_arc"
        ]
        return v.amount

    split = short([_R, _dwell(5), _dwell(5), _F, _dwell(120)])
    assert split == pytest.approx(short([_R, _dwell(10), _F, _dwell(120)]), abs=1e-12)


def test_a_run_of_dwells_is_one_dwell_everywhere():
    """Dwells in a row (and a dwell split at theta = 0) are one dwell: no station
    between the pieces, the residual vibration over the whole of it, Eq. 28's range
    within [0, 360] where the run crosses 0, and lifts that close to the model's
    tolerance (3 x 3.33333333 mm down after 10 mm up) leave one low dwell."""
    from camcore import train
    from camcore.analysis import stations
    from camcore.profile import geometry

    d = with_program([_R, _dwell(3), _dwell(67), _F, _dwell(60)])
    assert not np.any(np.isclose(np.degrees(stations(d, geometry(d))), 103.0))
    stiff = {"train_stiffness_N_per_m": 2e5}
    paper, split = (
        x.model_copy(update={"dynamics": x.dynamics.model_copy(update=stiff)})
        for x in (with_program(_PAPER), d)
    )
    ring = [
        [r["amplitude_mm"] for r in train.residual_vibration(x, train.respond(x))]
        for x in (paper, split)
    ]
    assert ring[1] == pytest.approx(ring[0], rel=1e-9)
    crossing = with_program([_dwell(5), _F, _dwell(120), _R, _dwell(5)])
    (v,) = [v for v in analyze(crossing, verify=False).violations if v.code == "high_dwell_arc"]
    assert v.ranges_deg == ((355.0, 360.0), (0.0, 5.0))
    third = _move("fall", 50, 3.33333333)
    near = with_program(
        [_dwell(30), _move("rise", 100, 10), _dwell(60), third, third, third, _dwell(20)]
    )
    codes = [g.code for g in motion.segments(near) if not g.is_motion]
    assert codes == [motion.LOW, motion.HIGH, motion.LOW]
    a = analyze(near)
    assert a.valid, [v.message for v in a.violations]
    assert len(summary(a)["dwells"]) == 2  # the high dwell and the split low one


def test_angles_summing_past_360_to_round_off_stay_within_the_cycle():
    """A program whose angles sum to 360.000001 deg (within the model's tolerance) and
    end with an empty dwell: no segment runs past 2 pi and the grid increases."""
    d = with_program(
        [
            _move("rise", 80, 7.5),
            _move("rise", 80, 7.5),
            _dwell(40),
            _move("fall", 160.000001, 15),
            _dwell(0),
        ],
        "single_roller",
    )
    assert all(0 <= g.start <= g.end <= 2 * math.pi for g in motion.segments(d))
    assert np.all(np.diff(analyze(d, verify=False).theta) > 0)


def test_theta_0_is_the_end_of_a_last_motion():
    """A program that ends with a motion and starts with a dwell: theta = 0 is that
    motion's end (2 pi), evaluated with its law. It had been the dwell's, so the fall
    lost its last sample and a roller undercut just there (r_b 16.08 mm, a 40 deg
    harmonic rise) was found in one rotation of the program and not in the other."""
    rise = _move("rise", 40, 15) | {"law": "simple_harmonic"}
    fall = _move("fall", 130, 15) | {"law": "simple_harmonic"}
    found = []
    for program in ([rise, _dwell(130), fall, _dwell(60)], [_dwell(130), fall, _dwell(60), rise]):
        data = with_program(program, "single_roller").model_dump(mode="json")
        data["cam"].update(base_radius_mm=16.0846, speed_rpm=100.0)
        data["limits"].update(max_pressure_angle_deg=89.0, require_continuous_acceleration=False)
        found.append(
            sorted(v.code for v in analyze(Design.model_validate(data), verify=False).violations)
        )
    assert found[0] == found[1] and "roller_undercut" in found[0]
    d = with_program([_dwell(60), _R, _dwell(70), _F])
    p = motion.program(d, np.array([0.0, 2 * math.pi - 1e-9]))
    assert p.segment[0] == motion.FALL and p.S[0] == pytest.approx(0.0, abs=1e-15)


@pytest.mark.parametrize("offset_mm", [-60.0, 45.0])
def test_stations_crop_follows_an_offset_follower(offset_mm):
    """A crop centred on the cam axis had an offset roller at its edge (30 mm) or out of
    it (further): the crops are centred on the contact points, so each station's contact
    lies in the middle half of its panel."""
    from camcore import document

    d = Design().with_kind(FollowerKind("single_roller"))
    d = d.model_copy(
        update={"follower": d.follower.model_copy(update={"single_offset_mm": offset_mm})}
    )
    a = analyze(d, verify=False)
    fig = document.stations_figure(a)
    for ax in [ax for ax in fig.axes if ax.axison]:
        (dot,) = [ln for ln in ax.lines if ln.get_marker() == "o"]
        x0, x1 = ax.get_xlim()
        x = float(dot.get_xdata()[0])
        assert x0 + 0.25 * (x1 - x0) < x < x1 - 0.25 * (x1 - x0)


def test_a_rise_into_a_rise_is_no_station_where_nothing_changes():
    """A designer's review: where one rise met the next, the station said "nothing
    changes", although a segment (its law, its lift) ends there."""
    from camcore.analysis import analyze
    from camcore.model import Design, load_preset
    from camcore.report import summary

    data = load_preset("paper_example").model_dump(mode="json")
    rise = {"kind": "rise", "angle_deg": 60, "law": "cycloidal"}
    data["motion"] = {
        "segments": [
            {**rise, "lift_mm": 8},
            {**rise, "lift_mm": 7},
            {"kind": "dwell", "angle_deg": 60},
            {"kind": "fall", "angle_deg": 120, "lift_mm": 15, "law": "cycloidal"},
            {"kind": "dwell", "angle_deg": 60},
        ]
    }
    events = [st["event"] for st in summary(analyze(Design.model_validate(data)))["stations"]]
    assert "station 1: one rise ends and the next begins" in events
    assert not any("nothing changes" in e for e in events)


def test_the_worst_of_many_alike_peaks_is_searched_whatever_the_resolution():
    """An adversarial review: five rises whose pressure-angle peaks agree to 1e-5 deg;
    the true worst (27.66595 deg, at 302.66 deg) lay in the fifth bracket, whose sample
    was lower, and only four are searched: the design passed at 5 and 0.1 deg and broke
    its 27.6657976 deg limit at 0.01 deg. Peaks are ranked by the parabola through
    their samples now, and the verdict holds at every resolution."""
    segs: list[dict] = []
    for _ in range(4):
        segs += [
            {"kind": "rise", "angle_deg": 30, "lift_mm": 10, "law": "cycloidal"},
            {"kind": "fall", "angle_deg": 42, "lift_mm": 10, "law": "cycloidal"},
        ]
    segs += [
        {"kind": "rise", "angle_deg": 30, "lift_mm": 9.088993, "law": "poly_4567"},
        {"kind": "fall", "angle_deg": 42, "lift_mm": 9.088993, "law": "cycloidal"},
    ]
    for res in (5.0, 0.1, 0.01):
        d = with_program(segs, kind="single_roller")
        data = d.model_dump(mode="json")
        data["cam"]["base_radius_mm"] = 60.0
        data["limits"].update(max_pressure_angle_deg=27.6657976, resolution_deg=res)
        a = analyze(Design.model_validate(data), verify=False)
        w = a.worst["pressure_angle_max"]
        assert math.degrees(w.value) == pytest.approx(27.665947, abs=1e-6)
        assert abs(math.degrees(w.theta) - 302.657) < 0.01
        assert "pressure_angle" in [v.code for v in a.violations]
