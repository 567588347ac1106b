"""Cutting the cam (issue 11): the cutter-centre path, its gouge check against the
cam's analytic curvature, and the G-code, read back."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from camcore import export, toolpath
from camcore.analysis import analyze
from camcore.export import ExportError
from camcore.model import Design, load_preset
from camcore.units import MM

PAPER = load_preset("paper_example")


def concave_roller_cam() -> Design:
    """A single-roller cam with a concave flank (rho < 0 on the rise)."""
    data = PAPER.with_kind("single_roller").model_dump(mode="json")
    data["cam"]["base_radius_mm"] = 20.0
    data["motion"]["rise_deg"] = 40.0
    return Design.model_validate(data)


def brute_distance(q: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Distance of each q to the closed polyline, every edge (the O(N M) reference)."""
    a, b = pts, np.roll(pts, -1, axis=0)
    ab = b - a
    out = np.empty(q.shape[0])
    for i, p in enumerate(q):
        t = np.clip(((p - a) * ab).sum(1) / (ab * ab).sum(1), 0, 1)
        out[i] = np.hypot(*(p - a - t[:, None] * ab).T).min()
    return out


def test_cutter_path_keeps_the_cutter_radius_from_the_cam():
    a = analyze(PAPER)
    D = 12 * MM
    path, bound = toolpath.cutter_path(a, D)
    dist = brute_distance(path, a.profile.points)
    np.testing.assert_allclose(dist, D / 2, atol=2 * a.chord_error + 1e-12)
    assert bound < 2 * a.chord_error  # the convex cam barely stretches its chords
    # the path runs round the cam at r_b + D/2 on the base circle
    rb = PAPER.cam.base_radius_mm * MM
    assert np.hypot(*path.T).min() == pytest.approx(rb + D / 2, abs=1e-6)


def test_the_cutter_may_not_be_wider_than_the_tightest_concave_stretch():
    """The geometric gouge check agrees with the analytic curvature (Eq. 21): a cutter
    3 % under twice the smallest concave radius passes, 3 % over is refused, with the
    cam angle of that radius inside a reported range."""
    d = concave_roller_cam()
    a = analyze(d)
    concave = np.where(a.in_contact & (a.rho < 0), -a.rho, np.inf)
    f, k = np.unravel_index(np.argmin(concave), concave.shape)
    rho_min = concave[f, k]
    toolpath.cutter_path(a, 2 * rho_min * 0.97)
    with pytest.raises(toolpath.GougeError) as err:
        toolpath.cutter_path(a, 2 * rho_min * 1.03)
    at = math.degrees(a.theta[k])
    ranges = [
        tuple(map(float, r.split("-")))
        for r in re.search(r"cam angles (.*) deg", str(err.value)).group(1).split(", ")
    ]
    assert any(lo - 1 <= at <= hi + 1 for lo, hi in ranges)
    # and the radius it names is the analytic one (the polyline's circle through three
    # vertices had said 66.4 mm for 66.04 in a designer's review)
    said = float(re.search(r"tightest concave radius is ([\d.]+) mm", str(err.value)).group(1))
    assert said == pytest.approx(rho_min / MM, rel=1e-4)
    from camcore.report import summary  # the report's figure, to the digits written

    assert f"{summary(a)['radius_of_curvature_mm']['concave_min']:.5g}" == f"{said:.5g}"
    # the diameter it promises fits (a maker's review: "at most twice that" gave no
    # number, and a cutter just over it passed)
    fits = float(re.search(r"at most twice that \(([\d.]+) mm\) always fits", str(err.value))[1])
    assert fits == pytest.approx(2 * said, rel=1e-3)
    toolpath.cutter_path(a, fits * MM)


def _first_pass(text: str):
    """The first pass as a controller reads it: (lead, moves) where each move is
    ("G1", end) or ("G2", end, centre), X Y from the feed onto the path to the lead-out,
    G words modal, I J incremental from the move's start."""
    mode, pos, moves, cutting = "G0", None, [], False
    for line in text.splitlines():
        if line.startswith("("):
            continue
        words = dict((w[0], w[1:]) for w in line.split() if w[0] in "GXYIJZ")
        mode = next((f"G{g}" for g in re.findall(r"G(\d+)", line) if g in "0123"), mode)
        if "Z" in words:
            if cutting and float(words["Z"]) > 0:
                break
            cutting = float(words["Z"]) < 0
            continue
        if "X" not in words:
            continue
        end = np.array([float(words["X"]), float(words["Y"])])
        if not cutting:
            pos = end  # the rapid to the lead-in point
            continue
        if mode == "G2":
            moves.append(("G2", end, pos + [float(words["I"]), float(words["J"])], pos))
        else:
            moves.append(("G1", end))
        pos = end
    return moves


def _sampled(moves, lead, step_deg: float = 0.01) -> np.ndarray:
    """The cutter centre's track through ``moves`` (arcs clockwise, sampled finely)."""
    pts = [lead]
    for m in moves:
        if m[0] == "G2":
            _, end, c, start = m
            a0 = math.atan2(*(start - c)[::-1])
            a1 = math.atan2(*(end - c)[::-1])
            sweep = (a0 - a1) % (2 * math.pi)  # clockwise
            t = a0 - np.linspace(0, sweep, max(2, int(math.degrees(sweep) / step_deg)))
            r = np.hypot(*(start - c))
            pts += list(c + r * np.column_stack([np.cos(t), np.sin(t)]))[1:]
        else:
            pts.append(m[1])
    return np.array(pts)


def test_gcode_reads_back_to_the_path():
    """Read as a controller would (G words modal, arcs clockwise about I J), the first
    pass feeds onto the path, cuts through every path vertex (to the rounding), ends
    where it began and leads out; each dwell is one G2 arc about the axis whose ends are
    equally far from it (a maker's review: the dwells had been chords)."""
    a = analyze(PAPER)
    D = 10 * MM
    text = toolpath.gcode(a, D)
    assert text.startswith("%\n") and "G21" in text and "M30" in text
    lead = np.array([float(v) for v in re.search(r"G0 X(-?[\d.]+) Y(-?[\d.]+)", text).groups()])
    moves = _first_pass(text)
    arcs = [m for m in moves if m[0] == "G2"]
    assert len(arcs) == 2  # the high and the low dwell (the contour starts at an arc's end)
    for _, end, c, start in arcs:
        assert np.allclose(c, 0.0, atol=1e-9)
        assert abs(np.hypot(*end) - np.hypot(*start)) < 2e-4
    r_arcs = sorted(round(float(np.hypot(*m[3])), 3) for m in arcs)
    s = __import__("camcore.report", fromlist=["summary"]).summary(a)
    assert r_arcs == [round(80.0 + 5.0, 3), round(s["dwell_radius_mm"] + 5.0, 3)]
    track = _sampled(moves, lead)
    path = toolpath.cutter_path(a, D)[0] / MM
    gap = toolpath.distance_to_polyline(path, track, 5.0)
    assert gap.max() < 2e-4  # every path vertex is cut (rounding to 0.1 um, arcs exact)
    cut = track[1:-1]
    np.testing.assert_allclose(cut[-1], cut[0], atol=1e-4)  # it closes ...
    area = 0.5 * np.sum(cut[:, 0] * np.roll(cut[:, 1], -1) - np.roll(cut[:, 0], -1) * cut[:, 1])
    assert area < 0  # ... clockwise (climb)
    assert len(moves) < path.shape[0] * 0.7  # the dwells' vertices are arcs now
    # the plunge happens off the part and off the blank: a cutter there clears a disc
    # of the cam's largest radius + D (a maker's review: it had plunged at r_b + 1.5 D,
    # half inside a blank of the cam's size), and the feed in runs along the ray
    R = np.hypot(*a.profile.points.T).max() / MM
    assert np.hypot(*lead) - D / MM / 2 >= R + D / MM - 1e-3
    assert abs(lead[0] * cut[0][1] - lead[1] * cut[0][0]) < 1e-3 * np.hypot(*lead)
    stated = float(re.search(r"blank of radius up to ([0-9.]+) mm", text).group(1))
    assert R + D / MM - 0.1 <= stated <= np.hypot(*lead) - D / MM / 2  # never overstated
    z = [float(m) for m in re.findall(r"Z(-?\d+\.\d+)", text)]
    assert z[0] > 0 and min(z) == pytest.approx(-PAPER.cam.width_mm) and z[-1] > 0


def test_design_name_cannot_break_out_of_a_gcode_comment():
    d = PAPER.model_copy(update={"name": "x) G0 Z-50 (\nM3"})
    text = toolpath.gcode(analyze(d, verify=False))
    for line in text.splitlines():
        if line.startswith("("):
            assert line.count("(") == 1 and line.count(")") == 1 and line.endswith(")")
    code = [line for line in text.splitlines() if not line.startswith("(")]
    assert not any("Z-50" in line for line in code)  # the name stays inside its comment


def test_gcode_header_says_what_the_operator_must_set():
    """The feeds are fixed defaults and the spindle speed is the operator's: the header
    says so, whole (a comment is cut at 80 characters)."""
    from camcore.analysis import analyze
    from camcore.model import load_preset
    from camcore.toolpath import gcode

    text = gcode(analyze(load_preset("paper_example"), verify=False))
    head = [line for line in text.splitlines() if line.startswith("(")]
    assert "(one pass, full depth, feed 200 plunge 50 mm/min)" in head
    assert "(feeds are defaults: check them for your machine and material)" in head
    assert "(no spindle speed given: M3 has no S word, set it before the run)" in head
    assert "(the cutter centre path, no cutter compensation G41/G42: G40)" in head
    assert "(one contour at final size: rough out a larger blank first)" in head
    assert "M3" in text.splitlines()
    # every Z word to the same 4 places (a designer's review: Z5.000 beside Z-15.0000)
    zs = re.findall(r"Z(-?\d+\.\d+)", text)
    assert zs and all(len(z.split(".")[1]) == 4 for z in zs)


def test_gcode_sets_up_safely_on_any_control():
    """A maker's review: the start line cancelled the operator's tool-length offset
    (G49) and named no work zero, the rapid height was fixed and the feed began as M3
    started the spindle. Now: G54 and no G49, with the header saying what to set; the
    design's rapid height on every rapid; a dwell after M3; and a name's parentheses
    kept as brackets (they had read '_double concave faces_')."""
    d = PAPER.model_copy(update={"cam": PAPER.cam.model_copy(update={"safe_height_mm": 42.5})})
    lines = toolpath.gcode(analyze(d, verify=False)).splitlines()
    code = [line for line in lines if not line.startswith("(")]
    assert "G54" in code[1].split() and not any("G49" in line for line in code)
    head = [line for line in lines if line.startswith("(")]
    assert "(work zero G54, no tool change and no length offset called: load the)" in head
    assert "(cutter and set its length offset first, G43 H on a Fanuc-style control)" in head
    assert "(rapids at Z42.5: above every clamp. No coolant called)" in head
    rapids = [line for line in code if line.startswith("G0 Z")]
    # up before moving over, down at rapid to 1 mm above the blank beside it (a review:
    # the plunge feed had run from the rapid height, a minute through air), home
    assert rapids == ["G0 Z42.5000", "G0 Z1.0000", "G0 Z42.5000"]
    m3 = code.index("M3")
    assert code[m3 + 1 : m3 + 3] == ["G4 P2", "G0 Z1.0000"] and code[m3 + 3].startswith("G1 Z-")
    assert "(cam contour: Chuang, Hsu & Chang, Section 6 example [double concave faces])" in head
    with pytest.raises(ValueError, match="safe_height_mm"):
        PAPER.cam.model_validate({**PAPER.cam.model_dump(), "safe_height_mm": 0.1})


def test_gcode_uses_the_designs_feeds_and_spindle_speed():
    """A maker's review: feeds and spindle speed were fixed. The design's own are
    written on every plunge and feed-in, S on M3, and the header no longer asks the
    operator to set what the design gives."""
    from camcore.analysis import analyze
    from camcore.model import load_preset
    from camcore.toolpath import gcode

    d = load_preset("paper_example")
    d = d.model_copy(
        update={
            "cam": d.cam.model_copy(
                update={
                    "feed_mm_per_min": 640.0,
                    "plunge_mm_per_min": 90.0,
                    "spindle_rpm": 4800.0,
                    "pass_depth_mm": 5.0,
                }
            )
        }
    )
    lines = gcode(analyze(d, verify=False)).splitlines()
    assert "M3 S4800" in lines and "M3" not in lines
    plunges = [x for x in lines if x.startswith("G1 Z-")]
    feeds_in = [x for x in lines if x.startswith("G1 X") and " F" in x]
    assert len(plunges) == 3 and all(x.endswith(" F90") for x in plunges)
    assert len(feeds_in) == 3 and all(x.endswith(" F640") for x in feeds_in)
    head = [x for x in lines if x.startswith("(")]
    assert "(3 passes of 5 mm, feed 640 plunge 90 mm/min)" in head
    assert not any("defaults" in x or "S word" in x for x in head)
    # plain decimals, never an exponent; below 1 (mm/min, rpm) is refused
    cam = d.cam.model_copy(update={"feed_mm_per_min": 100000.0, "spindle_rpm": 1234.5678})
    lines = gcode(analyze(d.model_copy(update={"cam": cam}), verify=False)).splitlines()
    assert "M3 S1234.568" in lines and all("e+" not in x and "e-" not in x for x in lines)
    assert any(x.endswith(" F100000") for x in lines)
    from camcore.model import DesignError, design_from_json

    for field, value in (
        ("feed_mm_per_min", 0.5),
        ("plunge_mm_per_min", 1e-5),
        ("spindle_rpm", 0.5),
    ):
        data = d.model_dump(mode="json")
        data["cam"][field] = value
        with pytest.raises(DesignError, match=field):
            design_from_json(__import__("json").dumps(data))


@pytest.mark.parametrize("tol_mm", [1e-3, 1e-4])
def test_the_header_bound_holds_for_the_written_coordinates(tol_mm):
    """The stated bound covers the path as written, coordinates rounded to DECIMALS
    places (a maker's review measured the file 0.04 um beyond a bound that left the
    rounding out, 74 % beyond it at a 0.1 um tolerance): every written vertex lies
    within the stated bound of the exact offset, i.e. within it less the path's own
    chordal bound of the unrounded vertex."""
    data = PAPER.model_dump()
    data["limits"]["export_tolerance_mm"] = tol_mm
    a = analyze(Design.model_validate(data), verify=False)
    D = 10 * MM
    text = toolpath.gcode(a, D)
    stated = float(re.search(r"path within ([0-9.e-]+) mm", text).group(1))
    path, bound = toolpath.cutter_path(a, D)
    xy = np.array([m[1] for m in _first_pass(text)])[:-1]  # the vertices written (not
    # the lead-out): each is a path vertex (an arc's inner ones are left out), rounded
    cw = path[::-1] / MM
    moved = max(np.hypot(*(cw - v).T).min() for v in xy)
    assert moved <= toolpath.ROUNDING_MM
    # an arc is the exact offset of a dwell: the circle about the axis, at the dwell's
    # radius + D/2, its radius as written (from the rounded start) within the bound
    from camcore.report import summary

    dwells = (80.0 + 5.0, summary(a)["dwell_radius_mm"] + 5.0)
    for m in _first_pass(text):
        if m[0] == "G2":
            assert min(abs(np.hypot(*m[3]) - r) for r in dwells) <= stated
    assert bound / MM + moved <= stated <= 1.01 * (bound / MM + toolpath.ROUNDING_MM)
    # Z is the cam width exactly, and the header says so in a whole comment
    assert "(Z-15 = the cam width exactly: add a breakthrough allowance)" in text.splitlines()


def _passes(text: str) -> list[list[tuple[float, float]]]:
    """The G-code's passes: the X Y words after each plunge (G1 Z-...)."""
    out: list[list[tuple[float, float]]] = []
    for line in text.splitlines():
        if line.startswith("G1 Z-"):
            out.append([])
        elif out and (m := re.search(r"X(-?\d+\.\d+) Y(-?\d+\.\d+)", line)):
            out[-1].append((float(m[1]), float(m[2])))
    return out


@pytest.mark.parametrize(
    ("width", "pass_depth", "breakthrough", "n"),
    [
        (15.0, 0.0, 0.0, 1),
        (15.0, 4.0, 0.0, 4),
        (15.0, 5.0, 0.0, 3),
        (15.0, 4.0, 0.5, 4),
        (20.0, 2.05, 0.5, 10),
    ],
)
def test_gcode_cuts_in_equal_passes_through_the_breakthrough(width, pass_depth, breakthrough, n):
    """As few equal passes as the pass depth allows, each the whole contour, the last
    at the width plus the breakthrough; the header says how many and how deep."""
    data = PAPER.model_dump()
    data["cam"].update(width_mm=width, pass_depth_mm=pass_depth, breakthrough_mm=breakthrough)
    d = Design.model_validate(data)
    assert d.cam.passes == n
    text = toolpath.gcode(analyze(d, verify=False), 10 * MM)
    z = [float(m) for m in re.findall(r"^G1 Z(-?\d+\.\d+)", text, flags=re.M)]
    np.testing.assert_allclose(z, -(width + breakthrough) * np.arange(1, n + 1) / n, atol=1e-4)
    if pass_depth:
        assert -np.diff([0.0, *z]).max() <= pass_depth + 1e-4
    passes = _passes(text)
    assert len(passes) == n and all(p == passes[0] for p in passes)
    assert passes[0][0] == passes[0][-2]  # onto the path, round it, and off to the lead point
    head = "\n".join(ln for ln in text.splitlines() if ln.startswith("("))  # the header
    assert ("one pass, full depth" if n == 1 else f"({n} passes of ") in head
    if breakthrough:
        assert (
            f"(Z-{width + breakthrough:g} = the cam width and {breakthrough:g} mm breakthrough)"
            in head
        )


def test_too_many_passes_is_refused_with_the_pass_depth_that_fits():
    """A rule of the G-code export, not of the design: the design is analysed and its
    other files made (a review: the report refused a design for its pass depth)."""
    data = PAPER.model_dump()
    data["cam"].update(width_mm=15.0, pass_depth_mm=0.1)  # 150 passes
    a = analyze(Design.model_validate(data), verify=False)
    assert a.valid and export.stl_bytes(a)
    with pytest.raises(
        ExportError, match=r"in 150 passes, more than 100 passes: use at least 0\.15 mm"
    ):
        toolpath.gcode(a)
    data["cam"]["pass_depth_mm"] = 0.15  # 15 / 0.15 = 100 up to rounding: allowed
    a = analyze(Design.model_validate(data), verify=False)
    assert a.design.cam.passes == 100 and "(100 passes of " in toolpath.gcode(a)
    data["cam"]["pass_depth_mm"] = 1e-308  # the ratio overflows: still a clear refusal
    with pytest.raises(
        ExportError, match=r"cut the 15 mm in more than 100 passes: use at least 0\.15"
    ):
        toolpath.gcode(analyze(Design.model_validate(data), verify=False))


def test_a_self_crossing_profile_is_refused_as_such_not_as_a_gouge():
    """r_b = 5 mm under the paper's 15 mm lift: the profile crosses itself. The G-code
    said a 10 mm cutter would gouge and to use one of 0.03 mm; STL and DXF said why."""
    data = PAPER.model_dump()
    data["cam"]["base_radius_mm"] = 5.0
    a = analyze(Design.model_validate(data), verify=False)
    assert not a.profile.is_star_shaped()
    with pytest.raises(ExportError, match="not star-shaped") as err:
        toolpath.gcode(a)
    assert not isinstance(err.value, toolpath.GougeError)


def test_a_gcode_file_beyond_a_million_moves_is_refused_with_a_pass_depth_that_fits():
    """100 passes of a 1e-5 mm profile (10,800 vertices) would be 20 MB of G-code (a
    large cam, 100 MB): refused, naming the least pass depth that fits, which fits."""
    data = PAPER.model_dump()
    data["limits"]["export_tolerance_mm"] = 1e-5
    data["cam"]["pass_depth_mm"] = 0.15  # 100 passes
    a = analyze(Design.model_validate(data), verify=False)
    moves = toolpath.cutter_path(a)[0].shape[0] + 2
    assert 100 * moves > toolpath.MAX_MOVES
    with pytest.raises(ExportError, match=r"at least ([0-9.]+) mm") as err:
        toolpath.gcode(a)
    least = float(re.search(r"at least ([0-9.]+) mm", str(err.value)).group(1))
    data["cam"]["pass_depth_mm"] = least
    fits = Design.model_validate(data)
    assert fits.cam.passes * moves <= toolpath.MAX_MOVES
    assert fits.cam.passes > 80  # the least that fits, not any


def test_the_header_says_the_bore_is_not_cut():
    """The program cuts the outside contour only; a maker must know the bore and its
    keyway are left to another operation."""
    data = PAPER.model_dump()
    assert "not cut here" not in toolpath.gcode(analyze(PAPER, verify=False))
    data["cam"].update(bore_diameter_mm=30.0, keyway_width_mm=8.0, keyway_depth_mm=3.3)
    text = toolpath.gcode(analyze(Design.model_validate(data), verify=False))
    assert "(not cut here: the 30 mm bore and its 8 x 3.3 mm keyway)" in text.splitlines()


def test_a_pass_deeper_than_the_cutter_is_flagged():
    """The full 15 mm width in one pass of a 10 mm cutter: the header cautions; in
    passes of 5 mm it does not."""
    text = toolpath.gcode(analyze(PAPER, verify=False))
    assert "(CAUTION: 15 mm per pass, more than the cutter diameter 10 mm:)" in text.splitlines()
    data = PAPER.model_dump()
    data["cam"]["pass_depth_mm"] = 5.0
    assert "CAUTION" not in toolpath.gcode(analyze(Design.model_validate(data), verify=False))


@pytest.mark.parametrize("preset", ["double_index", "indexer_345", "valve_lift_roller"])
@pytest.mark.parametrize("kind", [None, "single_roller", "flat_face"])
def test_every_program_is_cut_through_every_path_vertex(preset, kind):
    """Programs with several dwells, other followers: read back as a controller would,
    the track passes every path vertex (arcs and chords), and an arc is never cut where
    the cam is not a circle about the axis."""
    from camcore.model import load_preset

    d = load_preset(preset) if kind is None else load_preset(preset).with_kind(kind)
    a = analyze(d, verify=False)
    text = toolpath.gcode(a)
    lead = np.array([float(v) for v in re.search(r"G0 X(-?[\d.]+) Y(-?[\d.]+)", text).groups()])
    moves = _first_pass(text)
    d_mm = d.cam.cutter_diameter_mm / 2
    path = toolpath.cutter_path(a)[0] / MM
    assert toolpath.distance_to_polyline(path, _sampled(moves, lead), 5.0).max() < 2e-4
    cam_r = np.hypot(*a.profile.points.T) / MM
    for m in (m for m in moves if m[0] == "G2"):
        _, end, c, start = m
        near = np.hypot(*(path - start).T) < 1e-3  # the arc's start, a path vertex
        assert abs(cam_r[near][0] + d_mm - np.hypot(*(start - c))) < 1e-3
    assert sum(m[0] == "G2" for m in moves) >= 1


def test_a_long_header_note_is_wrapped_not_cut():
    """A maker's review: the edited-preset note was cut at 80 characters inside a field
    name ("cam.fe"). Every header comment is at most 80 characters, and the note's
    lines read back as the whole note."""
    from camcore.export import edited_note

    data = PAPER.model_dump()
    data["cam"].update(
        pass_depth_mm=4.0, breakthrough_mm=0.5, spindle_rpm=3000.0, feed_mm_per_min=300.0
    )
    d = Design.model_validate(data)
    lines = [ln for ln in toolpath.gcode(analyze(d, verify=False)).splitlines() if ln[:1] == "("]
    assert max(len(ln) for ln in lines) <= 80
    note = edited_note(d)
    assert len(note) > 80 and "cam.feed_mm_per_min" in note  # (the case cut before)
    assert note in " ".join(ln[1:-1].removeprefix("... ") for ln in lines)


def test_no_header_comment_starts_with_a_name_s_words():
    """A security review: a long design name, wrapped, put "(LOGOPEN,/path)" and
    "(MSG,...)" at the start of comment lines, which LinuxCNC acts on (LOGOPEN
    truncates the file it names). A comment line after the first starts "... "."""
    evil = "a" * 70 + " LOGOPEN,/home/cnc/mill.hal" + " " * 60 + "  MSG,Z_zero_set:skip_touch_off"
    d = PAPER.model_copy(update={"name": evil})
    lines = [ln for ln in toolpath.gcode(analyze(d, verify=False)).splitlines() if ln[:1] == "("]
    firsts = [ln[1:].lstrip().split(",")[0].split(" ")[0].upper() for ln in lines]
    assert not {"MSG", "LOGOPEN", "LOG", "DEBUG", "PRINT", "LOGCLOSE", "PROBEOPEN"} & set(firsts)
    assert any(ln.startswith("(... ") and "LOGOPEN" in ln for ln in lines)  # (wrapped)


@pytest.mark.parametrize(("cutter_mm", "tol_mm"), [(100.0, 0.001), (500.0, 0.1)])
def test_a_wide_cutter_s_path_holds_the_export_tolerance(cutter_mm, tol_mm):
    """Offsetting stretches a convex chord's sagitta by 1 + d kappa: on a 3 mm cam a
    500 mm cutter's path had run 2.5 mm inside the exact offset at a 0.1 mm tolerance
    (11 um at 1 um with 100 mm), its header stating so (an export review). The path is
    sampled finer now: every point of its chords, as the cutter runs them, keeps the
    cutter within the tolerance of the cam, measured against the cam sampled 100x finer
    than the tolerance."""
    data = load_preset("valve_lift_roller").model_dump()
    data["cam"].update(base_radius_mm=3.0, width_mm=2.0)
    data["motion"]["lift_mm"] = 1.0
    data["follower"]["roller_radius_mm"] = 1.0
    data["limits"]["export_tolerance_mm"] = tol_mm
    design = Design.model_validate(data)
    a = analyze(design, verify=False)
    path, bound = toolpath.cutter_path(a, cutter_mm * MM)
    data["limits"]["export_tolerance_mm"] = max(tol_mm / 100, 1e-5)
    fine = analyze(Design.model_validate(data), verify=False).profile.points / MM
    t = np.linspace(0.0, 1.0, 9)[:, None, None]
    p = path / MM
    along = (p + t * (np.roll(p, -1, axis=0) - p)).reshape(-1, 2)  # the chords as cut
    gap = toolpath.distance_to_polyline(along, fine, cutter_mm)
    assert gap.min() >= cutter_mm / 2 - tol_mm - 1e-5 - 2 * max(tol_mm / 100, 1e-5)
    assert bound / MM <= tol_mm
    stated = float(re.search(r"path within ([0-9.e-]+) mm", toolpath.gcode(a, cutter_mm * MM))[1])
    assert stated <= tol_mm + toolpath.ROUNDING_MM + 1e-9
