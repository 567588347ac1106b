"""Exports with a shaft bore: a watertight solid with the exact volume, a DXF circle."""

import dataclasses
import io
import math
import re

import ezdxf
import numpy as np
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st
from pydantic import ValidationError

from camcore import export, toolpath
from camcore.analysis import analyze
from camcore.model import Design, FollowerKind, edited_note, load_preset


def with_bore(diameter_mm: float, kind=FollowerKind.double_concave) -> Design:
    data = load_preset("paper_example").with_kind(kind).model_dump()
    data["cam"]["bore_diameter_mm"] = diameter_mm
    return Design.model_validate(data)


@pytest.mark.parametrize("kind", list(FollowerKind))
def test_bored_cam_is_watertight_with_exact_volume(kind):
    a = analyze(with_bore(25.0, kind), verify=False)
    mesh = trimesh.load(io.BytesIO(export.stl_bytes(a)), file_type="stl")
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0
    m = export.bore_chords(12.5, 2 * math.pi, a.design.limits.export_tolerance_mm)
    hole_mm2 = 0.5 * m * 12.5**2 * math.sin(2 * math.pi / m)  # the bore polygon
    assert mesh.volume == pytest.approx((a.profile.area * 1e6 - hole_mm2) * 15.0, rel=1e-6)
    # the hole goes right through: a closed surface of genus 1 (Euler number 0; 2 without)
    assert mesh.euler_number == 0
    solid = trimesh.load(io.BytesIO(export.stl_bytes(analyze(with_bore(0.0, kind)))), "stl")
    assert solid.euler_number == 2


def test_bore_in_dxf():
    a = analyze(with_bore(30.0), verify=False)
    doc = ezdxf.read(io.StringIO(export.dxf_bytes(a).decode()))
    bores = [e for e in doc.modelspace() if e.dxf.layer == "BORE"]
    assert len(bores) == 1 and bores[0].dxf.radius == pytest.approx(15.0)


def test_cut_only_dxf_and_what_the_files_say_they_are():
    """A maker's review: laser and waterjet software cuts every layer whatever its plot
    flag (the datum line and note would be cut), and the STL's header was all zeros.
    The cut-only DXF has PROFILE and BORE alone, the same outline as the full one; the
    STL header and a DATUM note say the program, the design and the tolerance; the
    design's name, user text, cannot break out of them."""
    data = _keyed().model_dump()
    data["name"] = 'evil"(x)'
    # a line break is a space already in the model (its name rule); the files' own
    # sanitizing is tested past it, on a design made without validation
    evil = Design.model_validate(data).model_copy(update={"name": 'evil\n  0\nSECTION"(x)'})
    a = analyze(evil, verify=False)
    full = ezdxf.read(io.StringIO(export.dxf_bytes(a).decode()))
    cut = ezdxf.read(io.StringIO(export.EXPORTS["dxf_cut"].write(a).decode()))
    assert {e.dxf.layer for e in cut.modelspace()} == {"PROFILE", "BORE"}
    for layer in ("PROFILE", "BORE"):
        (f,) = [e for e in full.modelspace() if e.dxf.layer == layer]
        (c,) = [e for e in cut.modelspace() if e.dxf.layer == layer]
        assert list(f.get_points()) == list(c.get_points())
    notes = [e.dxf.text for e in full.modelspace().query("TEXT")]
    assert any("cam evil_  0_SECTION_(x)" in t and "within 0.001 mm" in t for t in notes)
    for doc in (full, cut):  # the cut-only file too, as a drawing property
        assert doc.header.custom_vars.get("camdesigner").startswith("camdesigner ")
    stl = export.stl_bytes(a)
    assert stl[:80].startswith(b"camdesigner ") and b"cam evil_" in stl[:80]
    # the tolerance and unit come first: a long name is what the 80 bytes cut
    long = analyze(with_bore(0.0).model_copy(update={"name": "n" * 200}), verify=False)
    head = export.stl_bytes(long)[:80]
    assert b", mm, within 0.001 mm: cam nnn" in head and head.endswith(b"n")
    mesh = trimesh.load(io.BytesIO(stl), file_type="stl")
    assert mesh.is_watertight


def test_bore_larger_than_base_circle_is_rejected():
    with pytest.raises(ValidationError, match="bore_diameter_mm"):
        with_bore(160.0)


@settings(max_examples=25, deadline=None, derandomize=True)
@given(
    preset=st.sampled_from(
        ["paper_example", "indexer_345", "valve_lift_roller", "classroom_harmonic"]
    ),
    fraction=st.floats(min_value=0.0, max_value=0.999),
)
def test_any_bore_inside_the_base_circle_exports_a_solid(preset, fraction):
    d = load_preset(preset)
    data = d.model_dump()
    data["cam"]["bore_diameter_mm"] = fraction * 2 * d.cam.base_radius_mm
    data["limits"]["resolution_deg"] = 0.5
    a = analyze(Design.model_validate(data), verify=False)
    mesh = export.cam_mesh(a)
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0
    assert mesh.euler_number == (0 if fraction > 0 else 2)


@pytest.mark.parametrize("kind", [FollowerKind.double_roller, FollowerKind.double_concave])
@pytest.mark.parametrize("offset_mm", [0.0, 1e-9, 1e-6, 1e-4])
def test_tiny_offsets_give_watertight_stl_once_read_back(kind, offset_mm):
    """STL stores float32: contact points 1e-6 mm apart merge when read back. The export
    welds in float32 first, so the file as read is still a closed solid."""
    data = load_preset("paper_example").with_kind(kind).model_dump()
    data["follower"]["offset_mm"] = offset_mm
    a = analyze(Design.model_validate(data), verify=False)
    mesh = trimesh.load(io.BytesIO(export.stl_bytes(a)), file_type="stl")
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert mesh.volume == pytest.approx(a.profile.area * 1e6 * 15.0, rel=1e-7)


def test_weld_refuses_a_profile_that_turns_back():
    square = np.array([[1.0, 0], [0, 1], [-1, 0], [0.5, 0.9], [0, -1]])
    with pytest.raises(export.ExportError, match="not star-shaped"):
        export.weld_float32(square)


def _keyed(width=8.0, depth=3.3, bore=30.0, kind=FollowerKind.double_concave) -> Design:
    data = with_bore(bore, kind).model_dump()
    data["cam"].update(keyway_width_mm=width, keyway_depth_mm=depth)
    return Design.model_validate(data)


@pytest.mark.parametrize("kind", [FollowerKind.double_concave, FollowerKind.single_roller])
def test_keyway_solid_has_the_exact_volume(kind):
    """A keyed bore (DIN 6885-like 8 x 3.3 mm slot in a 30 mm bore): watertight, genus 1,
    and its volume is the profile area minus the hole's area (computed here
    independently: the circle's polygon plus the slot), times the width."""
    a = analyze(_keyed(kind=kind), verify=False)
    mesh = trimesh.load(io.BytesIO(export.stl_bytes(a)), file_type="stl")
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.euler_number == 0
    R, hw, top = 15.0, 4.0, 18.3
    foot = math.sqrt(R * R - hw * hw)
    # hole = the circle's segment polygon without the cap under the slot + the slot
    a_c = math.atan2(foot, hw)
    sweep = 2 * math.pi - (math.pi - 2 * a_c)  # the arc the outline follows
    m = export.bore_chords(R, sweep, a.design.limits.export_tolerance_mm)
    arc_poly = 0.5 * R * R * m * math.sin(sweep / m)  # fan of the arc chords
    hole = arc_poly + 0.5 * 2 * hw * foot + 2 * hw * (top - foot)  # + triangle + slot
    assert mesh.volume == pytest.approx((a.profile.area * 1e6 - hole) * 15.0, rel=1e-6)
    # the slot is on the +Y ray (theta = 0): the hole reaches y = top there
    inner = mesh.vertices[np.hypot(mesh.vertices[:, 0], mesh.vertices[:, 1]) < 20]
    assert inner[:, 1].max() == pytest.approx(top)
    assert inner[:, 1].min() == pytest.approx(-R, abs=0.01)


def test_keyway_in_dxf_and_datum_layers():
    a = analyze(_keyed(), verify=False)
    doc = ezdxf.read(io.StringIO(export.dxf_bytes(a).decode()))
    msp = doc.modelspace()
    bore = [e for e in msp if e.dxf.layer == "BORE"]
    assert len(bore) == 1 and bore[0].dxftype() == "LWPOLYLINE" and bore[0].closed
    pts = np.array([p[:2] for p in bore[0].get_points()])
    assert pts[:, 1].max() == pytest.approx(18.3)
    # three lines and one true arc of the bore's circle (CAM software sees a bore; a
    # maker's review found a 258-gon whose chords cut 1-3 um inside the circle)
    parts = list(bore[0].virtual_entities())
    arcs = [e for e in parts if e.dxftype() == "ARC"]
    assert sorted(e.dxftype() for e in parts) == ["ARC", "LINE", "LINE", "LINE"]
    (arc,) = arcs
    assert arc.dxf.radius == pytest.approx(15.0) and np.allclose(
        tuple(arc.dxf.center)[:2], 0, atol=1e-9
    )
    # it runs round the bottom (through -Y), from one foot of the slot to the other
    foot = math.degrees(math.atan2(math.sqrt(15.0**2 - 4.0**2), 4.0))
    assert arc.dxf.start_angle == pytest.approx(180 - foot)
    assert arc.dxf.end_angle % 360 == pytest.approx(foot)
    # reference layers: present, not plotted, no circle that looks like a feature
    for name in ("CENTERLINES", "DATUM"):
        assert doc.layers.get(name).dxf.plot == 0
    assert not [e for e in msp if e.dxftype() == "CIRCLE" and e.dxf.layer != "BORE"]
    datum = [e for e in msp if e.dxf.layer == "DATUM" and e.dxftype() == "LINE"][0]
    assert datum.dxf.start[0] == 0.0 == datum.dxf.end[0]  # on the theta = 0 ray (+Y)
    profile = [e for e in msp if e.dxf.layer == "PROFILE"][0]
    outline = list(ezdxf.path.make_path(profile).flattening(0.001))  # (arcs too)
    top = max(p[1] for p in outline if abs(p[0]) < 1.0)
    assert datum.dxf.end[1] == pytest.approx(top, abs=0.5)


@pytest.mark.parametrize("kind", ["double_concave", "single_roller"])
def test_the_dxf_draws_the_dwells_as_true_arcs(kind):
    """The profile's dwells are true arcs in the DXF (a maker's review: lasers and CAM
    programs take an arc as an arc): one per dwell, about the axis, of the dwell
    radius (Eq. 20) and the base radius, sweeping the arcs the report gives (Eqs. 24,
    26); every vertex of the profile lies on the DXF's outline, and the outline's
    extra points on the arcs lie on the circles."""
    from camcore.report import summary

    a = analyze(load_preset("paper_example").with_kind(kind), verify=False)
    s = summary(a)
    doc = ezdxf.read(io.StringIO(export.dxf_bytes(a, reference=False).decode()))
    (profile,) = [e for e in doc.modelspace() if e.dxf.layer == "PROFILE"]
    arcs = sorted(
        (e for e in profile.virtual_entities() if e.dxftype() == "ARC"),
        key=lambda e: -e.dxf.radius,
    )
    assert [round(e.dxf.radius, 6) for e in arcs] == [round(s["dwell_radius_mm"], 6), 80.0]
    for e, which in zip(arcs, ("high", "low"), strict=True):
        assert np.allclose(tuple(e.dxf.center)[:2], 0.0, atol=1e-9)
        swept = (e.dxf.end_angle - e.dxf.start_angle) % 360
        assert swept == pytest.approx(s["dwell_arc_deg"][which], abs=1e-3)
    # each profile vertex is a vertex of the outline, or lies on one of its arcs
    corners = {(round(x, 9), round(y, 9)) for x, y, *_ in profile.get_points()}
    for x, y in a.profile.points * 1e3:
        if (round(x, 9), round(y, 9)) in corners:
            continue
        polar = math.degrees(math.atan2(y, x))
        on = [
            e
            for e in arcs
            if (polar - e.dxf.start_angle) % 360 <= (e.dxf.end_angle - e.dxf.start_angle) % 360
        ]
        assert on and abs(math.hypot(x, y) - on[0].dxf.radius) < 1e-9, (x, y)
    assert len(profile) < a.profile.points.shape[0] * 0.7  # the arcs' vertices are gone


@pytest.mark.parametrize(
    "segments, offset, says",
    [
        (None, 0.0, "follower on this ray as the rise starts"),
        (
            "dwell first",
            0.0,
            "follower on this ray in a dwell at S=0 mm, the rise starts at THETA=60 deg",
        ),
        ("fall first", 0.0, "follower on this ray as the fall starts"),
        # (a review: "the rise starts at THETA=220 deg" where the fall starts at 30)
        (
            "high dwell first",
            0.0,
            "follower on this ray in a dwell at S=15 mm, the fall starts at THETA=30 deg",
        ),
        # (a review read "on this ray ... axis at X=-6 mm" as a contradiction)
        (None, 6.0, "follower stroke parallel to this ray, axis at X=-6 mm, as the rise starts"),
    ],
)
def test_the_datum_note_says_what_the_follower_does_at_theta_0(segments, offset, says):
    """A maker times the cam by the DXF's note: it had said 'as the rise starts' for a
    program that starts with a dwell (the rise 60 deg later) or a fall. The note is
    checked against the analysis: S at theta = 0 and where S first grows."""
    rise = {"kind": "rise", "angle_deg": 100, "lift_mm": 15, "law": "cycloidal"}
    fall = {"kind": "fall", "angle_deg": 130, "lift_mm": 15, "law": "cycloidal"}
    programs = {
        "dwell first": [
            {"kind": "dwell", "angle_deg": 60},
            rise,
            {"kind": "dwell", "angle_deg": 70},
            fall,
        ],
        "fall first": [
            fall,
            {"kind": "dwell", "angle_deg": 60},
            rise,
            {"kind": "dwell", "angle_deg": 70},
        ],
        "high dwell first": [
            {"kind": "dwell", "angle_deg": 30},
            fall,
            {"kind": "dwell", "angle_deg": 60},
            rise,
            {"kind": "dwell", "angle_deg": 40},
        ],
    }
    data = load_preset("paper_example").with_kind("single_roller").model_dump(mode="json")
    data["follower"]["single_offset_mm"] = offset
    if segments:
        data["motion"] = {"segments": programs[segments]}
    a = analyze(Design.model_validate(data), verify=False)
    doc = ezdxf.read(io.StringIO(export.dxf_bytes(a).decode()))
    text, label, *edited = [e.dxf.text for e in doc.modelspace() if e.dxftype() == "TEXT"]
    assert label.startswith("camdesigner ")  # the file says what it is
    assert edited == [edited_note(a.design)] if offset or segments else not edited
    lo, hi = np.array(doc.header["$EXTMIN"])[:2], np.array(doc.header["$EXTMAX"])[:2]
    P = a.profile.points * 1e3  # the extents hold the cam (viewers zoom to them)
    assert np.all(lo <= P.min(axis=0) + 1e-6) and np.all(hi >= P.max(axis=0) - 1e-6)
    # the notes stay inside the cam, so the extents are the cam's (a review: the
    # notes had reached 2.5 cam radii to the right, and a zoom to extents showed text)
    np.testing.assert_allclose(lo, P.min(axis=0), atol=0.01)  # (arcs bulge past vertices)
    np.testing.assert_allclose(hi, P.max(axis=0), atol=0.01)
    assert text == f"THETA=0: {says}; cam turns CW seen from +Z"
    grows = a.theta[np.argmax(a.prog.V > 1e-9)]  # where the rise starts
    falls = a.theta[np.argmax(a.prog.V < -1e-9)]  # where the fall starts
    if "the fall starts at" in says:
        assert a.prog.S[0] == pytest.approx(0.015) and math.degrees(falls) == pytest.approx(
            30.0, abs=0.2
        )
    elif "dwell" in says:
        assert a.prog.S[0] == 0.0 and math.degrees(grows) == pytest.approx(60.0, abs=0.2)
    elif "rise" in says:
        assert a.prog.S[0] == 0.0 and a.prog.V[1] > 0
    else:
        assert a.prog.S[0] == pytest.approx(0.015) and a.prog.V[1] < 0
    assert a.geo.stem_x == pytest.approx(-offset * 1e-3)


def test_a_d_flat_bore_is_cut_square_to_the_datum():
    """A D-flat bore for a motor's D shaft (a maker's review: without a keyway nothing
    on a printed or laser-cut cam fixed its phase): the STL is watertight with the
    volume of the profile less the D (computed here: the arc's fan of chords plus the
    triangle under the flat, close to the exact circle less its segment), the flat on
    the +Y ray 4 mm from the axis; in the DXF one line and one true arc; the G-code
    and the report say it."""
    from camcore.report import inputs_text

    data = with_bore(10.0).model_dump()
    data["cam"]["bore_flat_mm"] = 9.0  # a 10 mm D shaft, 9 mm across the flat
    a = analyze(Design.model_validate(data), verify=False)
    mesh = trimesh.load(io.BytesIO(export.stl_bytes(a)), file_type="stl")
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.euler_number == 0
    R, c = 5.0, 4.0
    hw = math.sqrt(R * R - c * c)
    sweep = math.pi + 2 * math.atan2(c, hw)
    m = export.bore_chords(R, sweep, a.design.limits.export_tolerance_mm)
    hole = 0.5 * R * R * m * math.sin(sweep / m) + hw * c
    exact = math.pi * R * R - (R * R * math.acos(c / R) - c * hw)
    assert hole == pytest.approx(exact, rel=1e-4)
    assert mesh.volume == pytest.approx((a.profile.area * 1e6 - hole) * 15.0, rel=1e-9)
    inner = mesh.vertices[np.hypot(mesh.vertices[:, 0], mesh.vertices[:, 1]) < 6]
    assert inner[:, 1].max() == pytest.approx(c) and inner[:, 1].min() == pytest.approx(
        -R, abs=1e-3
    )
    doc = ezdxf.read(io.StringIO(export.dxf_bytes(a, reference=False).decode()))
    (bore,) = [e for e in doc.modelspace() if e.dxf.layer == "BORE"]
    parts = list(bore.virtual_entities())
    assert sorted(e.dxftype() for e in parts) == ["ARC", "LINE"]
    (line,) = [e for e in parts if e.dxftype() == "LINE"]
    assert line.dxf.start[1] == pytest.approx(c) == line.dxf.end[1]
    assert abs(line.dxf.start[0] - line.dxf.end[0]) == pytest.approx(2 * hw)
    (arc,) = [e for e in parts if e.dxftype() == "ARC"]
    assert arc.dxf.radius == pytest.approx(R)
    assert (arc.dxf.end_angle - arc.dxf.start_angle) % 360 == pytest.approx(math.degrees(sweep))
    assert "(not cut here: the 10 mm bore with its flat, 9 mm across)" in toolpath.gcode(a)
    assert "D-flat bore, 9 mm across" in inputs_text(a.design)


@pytest.mark.parametrize(
    "change, message",
    [
        ({"bore_flat_mm": 4.5, "bore_diameter_mm": 0.0}, "a flat needs a bore"),
        ({"bore_flat_mm": 28.0, "keyway_width_mm": 8.0, "keyway_depth_mm": 3.0}, "not both"),
        ({"bore_flat_mm": 16.4}, r"between 0.55 and 0.98 x the bore diameter \(16.5 to 29.4"),
        ({"bore_flat_mm": 29.5}, "between 0.55 and 0.98 x the bore diameter"),
    ],
)
def test_bore_flat_limits(change, message):
    data = with_bore(30.0).model_dump()
    data["cam"].update(change)
    with pytest.raises(ValidationError, match=message):
        Design.model_validate(data)


@pytest.mark.parametrize(
    "change, message",
    [
        ({"keyway_width_mm": 8.0}, "give both"),
        ({"keyway_width_mm": 8.0, "keyway_depth_mm": 3.0, "bore_diameter_mm": 0.0}, "needs a bore"),
        ({"keyway_width_mm": 29.0, "keyway_depth_mm": 3.0}, "0.9 x the bore"),
        ({"keyway_width_mm": 8.0, "keyway_depth_mm": 70.0}, "past the base radius"),
    ],
)
def test_keyway_limits(change, message):
    data = with_bore(30.0).model_dump()
    data["cam"].update(change)
    with pytest.raises(ValidationError, match=message):
        Design.model_validate(data)


def test_the_outer_diameter_is_the_exact_cams_and_a_limit_when_set():
    """The cam's size (a maker's stock, a designer's envelope; no figure gave it),
    against closed forms: the paper's double concave faces' farthest points are on the
    high dwell arc of radius R (Eq. 20), 2R across; a radial single roller's cam is
    2 (r_b + h) across, at any export tolerance (a review: the chord error added to it
    had made 190.0013 mm, and 191.1 at a 1 mm tolerance). limits.max_outer_diameter_mm,
    when set, is checked against it."""
    from camcore import checks
    from camcore.report import summary

    def cam(limit=None, kind="double_concave", **limits):
        data = load_preset("paper_example").with_kind(kind).model_dump()
        data["limits"].update(max_outer_diameter_mm=limit, **limits)
        return analyze(Design.model_validate(data), verify=False)

    a = cam()
    size = checks.outer_diameter_mm(a)
    assert size == pytest.approx(2e3 * a.geo.dwell_radius, abs=1e-9)
    assert summary(a)["profile"]["outer_diameter_mm"] == size
    for tol in (0.001, 1.0):
        roller = cam(kind="single_roller", export_tolerance_mm=tol)
        assert checks.outer_diameter_mm(roller) == pytest.approx(2 * (80.0 + 15.0), abs=1e-9)
    assert "outer_diameter" not in {v.code for v in cam(190.0, "single_roller").violations}
    # why the farthest vertex is exact: the farthest point is where V = 0 (Eq. 4), at a
    # station or on a dwell, and every station's contact point is a vertex
    for kind in ("single_roller", "double_concave", "flat_face"):
        c = cam(kind=kind)
        for t in c.stations:
            touching = np.flatnonzero(c.in_contact[:, np.argmin(abs(c.theta - t))])
            for f in touching:
                r = np.hypot(*c.local(np.array([t])).point_world[f, 0])  # (any frame)
                assert np.isclose(np.hypot(*c.profile.points.T), r, rtol=0, atol=1e-12).any()
    assert "outer_diameter" not in {v.code for v in cam(190.0).violations}
    (v,) = [v for v in cam(189.0).violations if v.code == "outer_diameter"]
    assert v.amount == pytest.approx(size - 189.0) and f"{size:.4f} mm across" in v.message
    assert "limits.max_outer_diameter_mm" in v.message
    # what it proposes does it: the base radius less the half excess (and 1 % more)
    cut = f"about {(size - 189.0) / 2:.4g} mm less base radius"
    assert cut in v.message
    (v,) = [v for v in cam(20.0).violations if v.code == "outer_diameter"]
    assert "less base radius alone cannot (r_b is 80 mm)" in v.message  # (not "85 mm less")
    data = load_preset("paper_example").model_dump()
    data["cam"]["base_radius_mm"] -= 1.01 * (size - 189.0) / 2
    data["limits"]["max_outer_diameter_mm"] = 189.0
    smaller = analyze(Design.model_validate(data), verify=False)
    assert "outer_diameter" not in {v.code for v in smaller.violations}
    with pytest.raises(ValidationError, match="max_outer_diameter_mm"):
        Design.model_validate({"limits": {"max_outer_diameter_mm": -1.0}})


def test_a_hub_wall_below_the_limit_is_a_violation():
    """A bore that leaves a wall a maker cannot make (0.05 mm in the paper cam) passed
    every check and exported with exit 0 (a maker's review): limits.min_hub_wall_mm
    (default 2 mm) now says so, with the wall measured to the round bore (r_b - R) and
    to the keyway's corners (r_b - |corner|), less the chord error."""
    from camcore import checks

    def with_bore(bore, width=0.0, depth=0.0, wall_limit=2.0):
        data = load_preset("paper_example").model_dump()
        data["cam"].update(bore_diameter_mm=bore, keyway_width_mm=width, keyway_depth_mm=depth)
        data["limits"]["min_hub_wall_mm"] = wall_limit
        return analyze(Design.model_validate(data), verify=False)

    thin = with_bore(159.9)
    (v,) = [v for v in thin.violations if v.code == "hub_wall"]
    wall = checks.hub_wall_mm(thin)
    assert wall == pytest.approx(80.0 - 159.9 / 2, abs=2e-3)  # r_b - R, less the chords
    assert v.amount == pytest.approx(2.0 - wall) and f"is {wall:.4f} mm" in v.message
    keyed = with_bore(30.0, 8.0, 3.3)
    wall = 80.0 - math.hypot(4.0, 15.0 + 3.3)  # the base circle over the key's corners
    assert checks.hub_wall_mm(keyed) == pytest.approx(wall, abs=2e-3)
    assert "hub_wall" not in {v.code for v in keyed.violations}
    assert "hub_wall" in {v.code for v in with_bore(30.0, 8.0, 3.3, wall_limit=62.0).violations}
    assert checks.hub_wall_mm(with_bore(0.0)) is None  # a solid blank has no hub wall
    # a key's corner 0.3 mm under the base circle: the nearest point of the profile is
    # on an edge between two vertices ~0.8 mm apart, not at one (the review's case)
    depth = math.sqrt(80.0**2 - 4.0**2) - 0.3 - 15.0
    near = checks.hub_wall_mm(with_bore(30.0, 8.0, depth, wall_limit=0.0))
    assert near == pytest.approx(80.0 - math.hypot(4.0, 15.0 + depth), abs=2e-3)
    # a profile that repeats a vertex (a zero-length edge) still has a finite distance
    # (it was NaN, and a NaN wall read as broken; the property tests met it)
    from camcore.toolpath import distance_to_polyline

    square = np.array([[1.0, 0.0], [1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]])
    (d,) = distance_to_polyline(np.zeros((1, 2)), square, 10.0)
    assert d == pytest.approx(math.sqrt(0.5))
    from camcore.report import report_text, summary

    s = summary(keyed)
    assert s["profile"]["hub_wall_mm"] == checks.hub_wall_mm(keyed)  # reported, in mm
    assert f"{s['profile']['hub_wall_mm']:.3f} mm" in report_text(s)
    assert summary(with_bore(0.0))["profile"]["hub_wall_mm"] is None


@pytest.mark.parametrize("name", [r"a $\foo$ b", "cost $5 and $6", "$x^{$"])
def test_a_name_with_dollars_makes_a_pdf(name):
    """A review: matplotlib read a name's $...$ as math text, and r'a $\\foo$ b' made
    the PDF report fail (an internal error in the app); the other names are kept as
    cases (they made a PDF before too, the second with '$5 and $' set as math)."""
    d = load_preset("paper_example").model_copy(update={"name": name})
    data = export.EXPORTS["pdf"].write(analyze(d, verify=False))
    assert data.startswith(b"%PDF") and len(data) > 10_000


def test_the_drawn_profile_is_thinned_along_its_length():
    """A teacher's review: a constant-velocity rise refines the profile near its
    velocity jumps (tens of thousands of vertices there), and every k-th vertex left
    the 130 deg fall two chords, with the contact point off the drawn cam. The drawn
    (and displayed mesh's) vertices are even along the length: no gap much above the
    mean, every stretch of the cam drawn."""
    data = load_preset("paper_example").model_dump()
    data["motion"]["segments"][0]["law"] = "constant_velocity"
    a = analyze(Design.model_validate(data), verify=False)
    p = a.profile.points
    n = 1200
    idx = export.thin_evenly(p, n)
    q = p[idx]
    gaps = np.hypot(*np.diff(q, axis=0, append=q[:1]).T)
    edges = np.hypot(*np.diff(p, axis=0, append=p[:1]).T)
    mean = edges.sum() / n
    # (where the profile's own vertices are sparser than that, each is kept)
    assert p.shape[0] > 10 * n and len(idx) > n / 2
    assert gaps.max() < max(2.5 * mean, 1.01 * edges.max())
    assert np.all(np.diff(idx) > 0) and idx[0] == 0
    # the old stride left a gap of a fifth of the cam's perimeter
    stride = p[:: -(-p.shape[0] // n)]
    assert np.hypot(*np.diff(stride, axis=0).T).max() > 20 * mean
    assert export.thin_evenly(p[:10], n).tolist() == list(range(10))


@pytest.mark.parametrize("kind", ["double_concave", "single_concave", "flat_face"])
def test_the_follower_dxf_draws_faces_that_cover_every_contact(kind):
    """The follower's working faces (a maker's review: nothing gave them): every point
    where a face touches the cam, brought to zero lift, lies on the drawn arc (or line)
    and inside its ends, FACE_MARGIN_MM short of them at most; the drawing is readable."""
    a = analyze(load_preset("paper_example").with_kind(kind), verify=False)
    doc = ezdxf.read(io.StringIO(export.follower_dxf_bytes(a).decode()))
    assert not doc.audit().has_errors
    faces = [e for e in doc.modelspace() if e.dxf.layer == "FACE"]
    assert len(faces) == len(a.geo.faces) and doc.layers.get("NOTES").dxf.plot == 0
    for i, e in enumerate(faces):
        on = a.in_contact[i]
        p = a.point_world[i, on] * 1e3 - [a.geo.stem_x * 1e3, 0.0]
        p[:, 1] -= a.prog.S[on] * 1e3  # the follower at zero lift
        if e.dxftype() == "LINE":
            assert np.allclose(p[:, 1], e.dxf.start[1], atol=1e-9)
            ends = sorted((e.dxf.start[0], e.dxf.end[0]))
        else:
            c = np.array(tuple(e.dxf.center)[:2])
            assert e.dxf.radius == pytest.approx(250.0)
            assert np.allclose(np.hypot(*(p - c).T), 250.0, atol=1e-6)
            ends = sorted((e.start_point.x, e.end_point.x))
        assert ends[0] <= p[:, 0].min() <= ends[0] + export.FACE_MARGIN_MM + 1e-9
        assert ends[1] - export.FACE_MARGIN_MM - 1e-9 <= p[:, 0].max() <= ends[1]


def test_a_small_concave_face_is_drawn_within_its_circle():
    """A review: a valid cam with a 2.5 mm concave face failed the follower DXF with a
    math domain error (exit 3): its 2 mm margins reached past the face's circle. The
    arc now ends where the circle turns, and still covers every contact."""
    d = load_preset("paper_example").with_kind(FollowerKind.single_concave)
    data = d.model_dump()
    data["cam"].update(base_radius_mm=1.0, speed_rpm=100.0)
    data["follower"]["face_radius_mm"] = -2.5
    data["motion"] = {"lift_mm": 0.6, "rise_deg": 150.0, "fall_deg": 150.0, "high_dwell_deg": 40.0}
    a = analyze(Design.model_validate(data), verify=False)
    assert a.valid
    doc = ezdxf.read(io.StringIO(export.follower_dxf_bytes(a).decode()))
    (arc,) = [e for e in doc.modelspace() if e.dxf.layer == "FACE"]
    assert arc.dxf.radius == pytest.approx(2.5)
    cx = arc.dxf.center[0]
    ends = sorted((arc.start_point.x, arc.end_point.x))
    assert cx - 2.5 - 1e-9 <= ends[0] and ends[1] <= cx + 2.5 + 1e-9
    on = a.in_contact[0]
    x = a.point_world[0, on, 0] * 1e3 - a.geo.stem_x * 1e3
    assert ends[0] <= x.min() and x.max() <= ends[1]


def test_the_follower_dxf_draws_each_face_at_its_own_contact():
    """A double follower whose first face never touched: only the second face is drawn,
    over the second face's own stretch (a review: the spans were matched to the faces
    by position once the empty one was dropped, so face 1 got face 2's stretch)."""
    a = analyze(load_preset("paper_example"), verify=False)
    on = a.in_contact.copy()
    on[0] = False
    b = dataclasses.replace(a, in_contact=on)
    doc = ezdxf.read(io.StringIO(export.follower_dxf_bytes(b).decode()))
    (arc,) = [e for e in doc.modelspace() if e.dxf.layer == "FACE"]
    centre_x = (a.geo.faces[1].x_c - a.geo.stem_x) * 1e3
    assert arc.dxf.center[0] == pytest.approx(centre_x)
    x = (a.point_world[1, a.in_contact[1], 0] - a.geo.stem_x) * 1e3
    ends = sorted((arc.start_point.x, arc.end_point.x))
    assert ends[0] <= x.min() and x.max() <= ends[1]
    assert "concave face r_f" in " ".join(e.dxf.text for e in doc.modelspace().query("TEXT"))


@pytest.mark.parametrize(
    "kind, says",
    [
        ("single_roller", "its roller is a bearing (r_c 8 mm)"),
        ("double_roller", "its rollers are bearings"),
        ("knife_edge", "its tip is a point"),
    ],
)
def test_a_follower_without_a_face_to_draw_says_why(kind, says):
    a = analyze(load_preset("paper_example").with_kind(kind), verify=False)
    with pytest.raises(export.ExportError, match="has no face to draw: " + re.escape(says)):
        export.follower_dxf_bytes(a)


def test_an_edited_preset_says_so_wherever_its_files_name_it():
    """A preset edited in place keeps the preset's name: its files had labelled a part
    with another base radius as the paper's cam. They say it is edited, and what."""
    from camcore import document
    from camcore.report import report_text, summary

    paper = load_preset("paper_example")
    as_shipped = analyze(paper, verify=False)
    edited = paper.model_copy(update={"cam": paper.cam.model_copy(update={"base_radius_mm": 70})})
    a = analyze(edited, verify=False)
    note = "edited from preset paper_example: cam.base_radius_mm"
    assert edited_note(paper) is None and note not in export.file_label(as_shipped)
    assert export.file_label(a).endswith(f"cam {note}; {paper.name}")
    stl = export.stl_bytes(a)[:80]  # (80 bytes: the key, not the fields)
    assert stl.startswith(b"camdesigner ") and b"mm: edited paper_example: Chuang, Hsu" in stl
    dxf = ezdxf.read(io.StringIO(export.dxf_bytes(a).decode()))
    assert any(note in e.dxf.text for e in dxf.modelspace().query("TEXT"))
    assert "(edited from preset paper_example: cam.base_radius_mm)" in toolpath.gcode(a)
    assert report_text(summary(a), edited).splitlines()[:2] == [paper.name, f"({note})"]
    html = document.html_report(a)
    assert f"<title>Cam design report: {paper.name.replace('&', '&amp;')} ({note})</title>" in html
    assert f"({note})</p>" not in html and f"({note}) &nbsp;" in html  # beside the name
    pdf = document.pdf_report(a)  # (its Info dictionary escapes parentheses)
    assert rb"\(edited from preset paper_example: cam.base_radius_mm\))" in pdf
    assert "edited" not in report_text(summary(as_shipped), paper)
    # Table 1's comparison renames the follower in the name: the kind is then no edit
    roller = paper.with_kind("single_roller")
    assert roller.name != paper.name and edited_note(roller) is None
    # one name, many edits: three named, the rest counted
    data = edited.model_dump(mode="json")
    data["follower"]["kind"] = "single_roller"
    data["cam"]["speed_rpm"] = 100
    data["material"]["grade"] = "bronze"
    assert edited_note(Design.model_validate(data)) == (
        "edited from preset paper_example: follower.kind, cam.base_radius_mm, "
        "cam.speed_rpm and 1 more"
    )
    # a name of the user's own names no preset
    assert edited_note(edited.model_copy(update={"name": "my cam"})) is None


@pytest.mark.parametrize("bore, keyway", [(79.0, None), (60.0, (16.0, 4.3))])
def test_the_bore_is_within_the_export_tolerance(bore, keyway):
    """A maker's review: a 79 mm bore was a 256-gon whose flats sat 2.97 um inside the
    circle, under an STL header saying "within 0.001 mm". Every chord of the bore in
    the mesh (found by their radius, not by the code's count) stays within the
    tolerance of the circle, its vertices on it."""
    data = load_preset("valve_lift_roller").model_dump()
    data["cam"]["bore_diameter_mm"] = bore  # (a 256-gon: 2.97 / 2.26 um inside)
    if keyway:
        data["cam"].update(keyway_width_mm=keyway[0], keyway_depth_mm=keyway[1])
    a = analyze(Design.model_validate(data), verify=False)
    tol, R = a.design.limits.export_tolerance_mm, bore / 2
    mesh = trimesh.load(io.BytesIO(export.stl_bytes(a)), file_type="stl")
    assert mesh.is_watertight
    ring = mesh.vertices[(mesh.vertices[:, 2] == 0.0)][:, :2]
    r = np.hypot(*ring.T)
    on = ring[np.abs(r - R) < 1e-4]  # the circle's vertices (not the slot's corners)
    assert on.shape[0] > 256 and np.abs(np.hypot(*on.T) - R).max() < 1e-4
    t = np.sort(np.arctan2(on[:, 1], on[:, 0]))
    step = np.diff(t)
    if keyway:  # (the slot's gap between the feet is no chord of the circle)
        step = step[step < 0.1]
    else:
        step = np.append(step, t[0] + 2 * math.pi - t[-1])
    sagitta = R * (1 - np.cos(step / 2))
    assert sagitta.max() <= tol * (1 + 1e-6)


def test_the_series_numbers_the_programs_own_segments():
    """A designer's review: a program of four segments (rise, dwell, fall, rise) read
    0, 1, 2, 4 in the series' segment column (motion.segments adds an empty dwell
    between the fall and the rise). The column numbers the program's segments from 1,
    as the app's table does."""
    data = load_preset("paper_example").model_dump(mode="json")
    data["motion"] = {
        "segments": [
            {"kind": "rise", "angle_deg": 120, "lift_mm": 20, "law": "cycloidal"},
            {"kind": "dwell", "angle_deg": 60},
            {"kind": "fall", "angle_deg": 120, "lift_mm": 25, "law": "cycloidal"},
            {"kind": "rise", "angle_deg": 60, "lift_mm": 5, "law": "cycloidal"},
        ]
    }
    a = analyze(Design.model_validate(data), verify=False)
    cols = export.series_columns(a)
    seg, th = cols["segment"], cols["theta_deg"]
    assert sorted(set(seg.tolist())) == [1, 2, 3, 4]
    for lo, hi, row in ((0, 120, 1), (120, 180, 2), (180, 300, 3), (300, 360, 4)):
        inside = (th > lo + 0.05) & (th < hi - 0.05)
        assert np.all(seg[inside] == row), (lo, hi, row)


def test_a_bore_that_crosses_the_profile_s_chords_is_refused():
    """An adversarial review: a 159.9 mm bore at a 1 mm tolerance cleared the profile's
    80 mm vertices but crossed its chords (79.45 mm from the axis), and the STL's caps
    overlapped themselves (59 triangles inverted); trimesh still called it watertight."""
    data = load_preset("paper_example").model_dump(mode="json")
    data["limits"]["export_tolerance_mm"] = 1.0
    data["cam"]["bore_diameter_mm"] = 159.9
    a = analyze(Design.model_validate(data), verify=False)
    radii = np.hypot(*a.profile.points.T) * 1e3
    assert radii.min() > 159.9 / 2  # every vertex clears the bore: only a chord cuts it
    with pytest.raises(export.ExportError, match=r"its chords come to ([0-9.]+) mm") as err:
        export.stl_bytes(a)
    chords = float(re.search(r"its chords come to ([0-9.]+) mm", str(err.value))[1])
    q = a.profile.points * 1e3  # a convex cam: each chord's nearest point is its line's
    d = np.roll(q, -1, axis=0) - q
    lines = np.abs(q[:, 0] * d[:, 1] - q[:, 1] * d[:, 0]) / np.hypot(*d.T)
    assert chords == pytest.approx(lines.min(), abs=1e-4) and chords < 159.9 / 2


def test_the_stl_states_what_its_32_bit_floats_add_to_the_tolerance():
    """An adversarial review: a 400 mm cam exported at 1e-5 mm was stored up to
    2.1e-5 mm off the exact cam (STL keeps 32-bit floats: ~3e-5 mm there), under a
    header saying "within 1e-05 mm". The header adds the rounding; at the usual sizes
    it is under 1 % of the tolerance, and the header says the tolerance alone."""
    import re

    data = load_preset("paper_example").model_dump(mode="json")
    data["limits"]["export_tolerance_mm"] = 1e-5
    data["cam"]["base_radius_mm"] = 400.0
    data["follower"]["face_radius_mm"] = -1000.0
    a = analyze(Design.model_validate(data), verify=False)
    blob = export.stl_bytes(a)
    stated = float(re.search(rb"within ([0-9.e+-]+) mm", blob[:80])[1])
    p = a.profile.points * 1e3
    rounding = np.abs(p.astype(np.float32).astype(np.float64) - p).max()
    assert rounding > 1e-5 and stated >= 1e-5 + rounding
    paper = export.stl_bytes(analyze(load_preset("paper_example"), verify=False))
    assert b"within 0.001 mm" in paper[:80]


@pytest.mark.parametrize(
    "program",
    [
        None,  # the paper's: theta = 0 on the low dwell's true arc
        [  # no dwell, an offset roller: +Y crosses a chord
            {"kind": "rise", "angle_deg": 180.0, "lift_mm": 20.0, "law": "cycloidal"},
            {"kind": "fall", "angle_deg": 180.0, "lift_mm": 20.0, "law": "cycloidal"},
        ],
    ],
)
def test_the_datum_line_ends_on_the_outline_as_cut(program):
    """The DATUM line runs out to the PROFILE polyline where it crosses the +Y ray, on a
    chord or on a dwell's true arc, also at a coarse tolerance (it ended at the nearest
    vertex: 0.14 mm short at 1 mm)."""
    d = load_preset("paper_example").model_copy(deep=True)
    d.limits.export_tolerance_mm = 1.0
    if program is not None:
        d = d.with_kind(FollowerKind.single_roller)
        d.follower.single_offset_mm = 5.0  # (theta = 0's contact off the +Y ray)
        d = Design.model_validate({**d.model_dump(), "motion": {"segments": program}})
    doc = ezdxf.read(io.StringIO(export.dxf_bytes(analyze(d, verify=False)).decode()))
    msp = doc.modelspace()
    datum = [e for e in msp if e.dxf.layer == "DATUM" and e.dxftype() == "LINE"][0]
    (profile,) = [e for e in msp if e.dxf.layer == "PROFILE"]
    tops = []  # where ezdxf's own lines and arcs of the outline cross the +Y ray
    for e in profile.virtual_entities():
        if e.dxftype() == "ARC":
            if (90.0 - e.dxf.start_angle) % 360 <= (e.dxf.end_angle - e.dxf.start_angle) % 360:
                tops.append(e.dxf.radius)
        elif (e.dxf.start[0] >= 0) != (e.dxf.end[0] >= 0):
            (x0, y0, _), (x1, y1, _) = e.dxf.start, e.dxf.end
            tops.append(y0 + (y1 - y0) * x0 / (x0 - x1))
    top = max(tops)
    assert datum.dxf.end[1] == pytest.approx(top, abs=1e-5)
