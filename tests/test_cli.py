"""The command line contract: report --json keys, compare, export files, errors."""

import io
import json
import math
import re
import subprocess
import sys

import ezdxf
import numpy as np
import pytest
import trimesh

from camcore.cli import main
from camcore.model import PAPER_FOLLOWERS, FollowerKind, design_to_json, load_preset, preset_names

KEYS = {
    "follower",
    "valid",
    "violations",
    "dwell_radius_mm",
    "psi_h_deg",
    "psi_l_deg",
    "stations_deg",
    "pressure_angle_max_deg",
    "curvature_radius_mm",
    "contact_force_max_N",
    "guide_force_max_N",
    "contact_stress_max_MPa",
    "profile",
    "verification",
}


def run_json(capsys, *args):
    assert main(list(args)) == 0
    return json.loads(capsys.readouterr().out)


@pytest.mark.parametrize("kind", [k.value for k in FollowerKind])
def test_report_json_contract(capsys, kind):
    s = run_json(capsys, "report", "--preset", "paper_example", "--follower", kind, "--json")
    assert KEYS <= s.keys()
    assert s["follower"] == kind and s["valid"] is True and s["violations"] == []
    assert len(s["stations_deg"]) == 6
    assert set(s["pressure_angle_max_deg"]) == {"rise", "fall"}
    assert len(s["curvature_radius_mm"]["rise"]) == 2
    assert set(s["contact_force_max_N"]) >= {"cycle", "high_dwell"}
    assert set(s["guide_force_max_N"]) == {"F1", "F2"}
    assert set(s["contact_stress_max_MPa"]) == {"cycle", "high_dwell", "high_dwell_two_contact"}
    v = s["verification"]
    assert v["max_lift_error_mm"] <= v["allowed_lift_error_mm"] < 2e-3
    assert v["chord_error_mm"] <= v["export_tolerance_mm"] == 1e-3
    # the cam lies between the base circle (r_b = 80 mm) and the dwell circle
    assert math.pi * 80**2 < s["profile"]["area_mm2"] < math.pi * s["dwell_radius_mm"] ** 2
    assert 2 * math.pi * 80 < s["profile"]["perimeter_mm"] < 2 * math.pi * s["dwell_radius_mm"]


def test_report_from_file_and_text(tmp_path, capsys):
    path = tmp_path / "d.json"
    path.write_text(load_preset("paper_example").model_dump_json())
    assert main(["report", str(path)]) == 0
    out = capsys.readouterr()
    assert "double_concave" in out.out and "Eq. 20" in out.out
    assert "not in the file" not in out.err  # a complete file: nothing to say
    # the inputs head the text report (a review: a value a file left out went unseen),
    # and a figure that does not apply is "-", not "- mm"
    assert "r_b 80 mm, width 15 mm, 1200 rpm" in out.out and "E 210 GPa nu 0.29" in out.out
    # and how it is to be made (a maker's review: the shop's report had only the bore)
    assert (
        "  making    no keyway; G-code: cutter 10 mm, 1 pass, breakthrough 0 mm, feed 200 / "
        "plunge 50 mm/min, spindle not given, rapids 5 mm\n" in out.out
    )
    assert out.out.index("program   1. rise 100 deg 15 mm cycloidal") < out.out.index("Eq. 20")
    assert "acceleration continuous; no jump at 1200 rpm\n" in out.out  # the limits line
    assert "flat face width needed               -\n" in out.out and "  - mm" not in out.out
    data = json.loads(path.read_text())
    data["limits"]["min_jump_speed_ratio"] = 1.6  # a margin (the design jumps at 1.55 x)
    path.write_text(json.dumps(data))
    assert main(["report", str(path)]) == 1
    text = capsys.readouterr().out
    assert "no jump up to 1.6 x 1200 = 1920 rpm\n" in text and "jump_speed" in text


def test_a_file_leaving_inputs_out_says_which_took_defaults(tmp_path, capsys):
    """A review: a file without the base radius, or ``{}``, was analysed as the paper
    example ("valid yes") without a word. The inputs left out are named, with the
    values they took; fields a follower does not use are not."""
    data = json.loads(design_to_json(load_preset("paper_example")))
    del data["cam"]["base_radius_mm"], data["dynamics"], data["follower"]["roller_radius_mm"]
    path = tmp_path / "d.json"
    path.write_text(json.dumps(data))
    assert main(["report", str(path)]) == 0
    err = capsys.readouterr().err
    assert "cam.base_radius_mm = 80.0" in err and "dynamics (the whole group)" in err
    assert "roller_radius_mm" not in err  # a concave face has no roller
    path.write_text("{}")
    assert main(["report", str(path)]) == 0
    assert "motion (the whole group)" in capsys.readouterr().err
    # said of the design analysed: a --set value is not a default, and a follower
    # --follower brings in says the roller radius it took (a review of the note)
    path.write_text(json.dumps(data))
    args = ["report", str(path), "--set", "cam.base_radius_mm=90", "--follower", "double_roller"]
    assert main(args) == 0
    err = capsys.readouterr().err
    assert "base_radius_mm" not in err and "follower.roller_radius_mm = 8.0" in err
    assert "follower.kind" not in err  # --follower gave it
    # a group left out but partly given on the command line: its other fields named
    assert main(["report", str(path), "--set", "dynamics.mass_g=200"]) == 0
    err = capsys.readouterr().err
    assert "dynamics (the whole group)" not in err and "dynamics.mass_g" not in err
    assert "dynamics.spring_rate_N_per_m = 6772.5" in err
    # a classic motion given in part (a file, or --set on a file without one): the
    # angles and laws it left out are named too (a README review)
    path.write_text(json.dumps({"motion": {"lift_mm": 16, "rise_deg": 90}}))
    assert main(["report", str(path)]) == 0
    err = capsys.readouterr().err
    assert "motion.fall_deg = 130.0" in err and "motion.rise_law = cycloidal" in err
    assert "motion.rise_deg" not in err and "motion.lift_mm" not in err
    path.write_text("{}")
    assert main(["report", str(path), "--set", "motion.lift_mm=16"]) == 0
    err = capsys.readouterr().err
    assert "motion.high_dwell_deg = 70.0" in err and "motion.lift_mm" not in err


def test_violations_are_reported_with_equation(capsys):
    s = run_json(capsys, "report", "--preset", "paper_example", "--json")
    assert s["valid"]
    d = load_preset("paper_example").model_dump()
    d["motion"]["high_dwell_deg"] = 10  # below 4 psi_h = 14.8 deg
    d["cam"]["speed_rpm"] = 6000  # the spring cannot hold the follower
    from camcore.analysis import analyze
    from camcore.model import Design

    a = analyze(Design.model_validate(d))
    codes = {v.code: v for v in a.violations}
    assert codes["high_dwell_arc"].equation == "Eq. 28"
    assert codes["high_dwell_arc"].amount == pytest.approx(4 * math.degrees(a.geo.psi_h) - 10)
    assert codes["jump"].equation == "Eqs. 29-41" and codes["jump"].ranges_deg


def test_compare_table(capsys):
    rows = run_json(capsys, "compare", "--preset", "paper_example", "--json")
    assert [r["follower"] for r in rows] == [k.value for k in PAPER_FOLLOWERS]
    assert main(["compare", "--preset", "paper_example"]) == 0
    assert "Table 1" in capsys.readouterr().out
    rows = run_json(
        capsys,
        "compare",
        "--preset",
        "paper_example",
        "--json",
        "--followers",
        "flat_face,single_roller,knife_edge",
    )
    assert [r["follower"] for r in rows] == ["flat_face", "single_roller", "knife_edge"]
    assert rows[0]["paper_table1_N"] is None and rows[1]["paper_table1_N"] == 133.496
    # Table 1 speaks of the paper's example only: not beside another cam, nor in words
    for change in ("cam.base_radius_mm=120", "dynamics.mass_g=200", "follower.offset_mm=12"):
        other = run_json(capsys, "compare", "--preset", "paper_example", "--set", change, "--json")
        assert all(r["paper_table1_N"] is None for r in other), change
    main(["compare", "--preset", "paper_example", "--set", "cam.base_radius_mm=120"])
    assert "shown for the paper_example design only" in capsys.readouterr().out
    same = "cam.width_mm=20"  # width, material, limits: Table 1's F_N does not depend on them
    # the geometry the followers differ in most, as each one's own report gives it
    one = run_json(capsys, "report", "--preset", "paper_example", "--json")
    (dc,) = [
        r
        for r in run_json(capsys, "compare", "--preset", "paper_example", "--json")
        if r["follower"] == "double_concave"
    ]
    assert dc["pressure_angle_rise_deg"] == one["pressure_angle_max_deg"]["rise"]
    assert dc["rho_convex_min_mm"] == one["radius_of_curvature_mm"]["convex_min"]
    assert dc["outer_diameter_mm"] == one["profile"]["outer_diameter_mm"]  # (the size too)
    main(["compare", "--preset", "paper_example"])
    assert "outer diameter" in capsys.readouterr().out
    kept = run_json(capsys, "compare", "--preset", "paper_example", "--set", same, "--json")
    assert [r["paper_table1_N"] for r in kept] == [133.496, 67.297, 129.161, 67.297]
    assert rows[2]["stress_max_MPa"] is None  # a knife edge has no Hertz stress
    assert main(["compare", "--preset", "paper_example", "--followers", "wheel"]) == 2


def test_compare_says_each_verdict_and_each_unbounded_figure(tmp_path, capsys):
    """A designer's review: compare's verdicts went to stderr only, so a table written
    to a file read as all good beside 2,004,164 MPa at a cusp; and the defaults a file
    left out were named for the design's own follower only, not for the others it
    compared. The text ends with each follower's limits, and a figure without a bound
    is said under it (JSON: "unbounded"); the note names every compared kind's field."""
    bad = ["--set", "motion.lift_mm=40", "--set", "cam.base_radius_mm=30"]
    assert main(["compare", "--preset", "paper_example", "--json", *bad]) == 1
    rows = json.loads(capsys.readouterr().out)
    assert main(["compare", "--preset", "paper_example", *bad]) == 1
    out = capsys.readouterr().out
    verdicts = out[out.rindex("limits") :]
    for r in rows:
        said = "met" if r["valid"] else "BREAKS " + ", ".join(r["breaks"])
        assert f"{r['follower']:>14}  {said}" in verdicts
        for note in r["unbounded"]:
            assert f"!! {note}" in verdicts
    cusped = [r for r in rows if any("cusp" in n for n in r["unbounded"])]
    assert cusped and all("curvature_convex (Eq. 22)" in r["breaks"] for r in cusped)
    assert all(r["unbounded"] == [] for r in rows if r["valid"])
    # a file leaving out fields of the other followers: named too
    data = json.loads(design_to_json(load_preset("paper_example").with_kind("single_roller")))
    del data["follower"]["face_radius_mm"], data["follower"]["offset_mm"]
    path = tmp_path / "roller.json"
    path.write_text(json.dumps(data))
    assert main(["compare", str(path)]) == 0
    err = capsys.readouterr().err
    assert "follower.face_radius_mm = -250.0" in err and "follower.offset_mm = 10.0" in err
    assert main(["report", str(path)]) == 0  # the roller alone: not its fields
    assert "face_radius_mm" not in capsys.readouterr().err


def test_export_files(tmp_path, capsys):
    out = {ext: tmp_path / f"cam.{ext}" for ext in ("stl", "dxf", "csv", "json")}
    assert (
        main(
            [
                "export",
                "--preset",
                "paper_example",
                "--stl",
                str(out["stl"]),
                "--dxf",
                str(out["dxf"]),
                "--csv",
                str(out["csv"]),
                "--json",
                str(out["json"]),
            ]
        )
        == 0
    )
    err = capsys.readouterr().err
    assert err.count("wrote") == 4
    assert "note: no shaft bore" in err  # the paper's cam has none: a solid disc
    s = run_json(capsys, "report", "--preset", "paper_example", "--json")
    mesh = trimesh.load(out["stl"], file_type="stl")
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert mesh.volume == pytest.approx(s["profile"]["area_mm2"] * 15.0, rel=1e-6)
    assert mesh.bounds[1][2] - mesh.bounds[0][2] == pytest.approx(15.0)
    doc = ezdxf.readfile(out["dxf"])
    poly = [e for e in doc.modelspace() if e.dxftype() == "LWPOLYLINE"][0]
    pts = np.array([p[:2] for p in poly.get_points()])
    assert poly.closed and np.hypot(*pts.T).min() == pytest.approx(80.0, abs=1e-6)
    rows = out["csv"].read_text().splitlines()
    assert rows[0].startswith("cam_angle_deg,x_mm,y_mm")
    assert len(rows) - 1 == s["profile"]["vertices"]
    from camcore.model import design_from_json

    assert design_from_json(out["json"].read_text()) == load_preset("paper_example")


@pytest.mark.parametrize(
    "args, message",
    [
        (["report", "/no/such/file.json"], "cannot read"),
        (["report"], "give a design file or --preset"),
        (["report", "--preset", "nope"], "no preset 'nope'"),
        (["export", "--preset", "paper_example"], "nothing to export"),
    ],
)
def test_errors_are_one_line(args, message):
    proc = subprocess.run(
        [sys.executable, "-m", "camcore.cli", *args], capture_output=True, text=True
    )
    assert proc.returncode == 2
    assert message in proc.stderr and "Traceback" not in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1


def test_invalid_value_names_field(tmp_path):
    d = load_preset("paper_example").model_dump()
    d["cam"]["base_radius_mm"] = -5
    p = tmp_path / "bad.json"
    p.write_text(json.dumps(d))
    proc = subprocess.run(
        [sys.executable, "-m", "camcore.cli", "report", str(p)], capture_output=True, text=True
    )
    assert proc.returncode == 2 and "cam.base_radius_mm: " in proc.stderr
    assert "(got -5)" in proc.stderr  # the value refused, too
    assert "Traceback" not in proc.stderr


@pytest.mark.parametrize("raw", ["nan", "NaN", "-inf", "Infinity", " inf"])
def test_every_spelling_of_a_non_number_is_refused_alike(raw, capsys):
    """A review: '=nan' said 'Input should be a valid number', '=NaN' said what is
    wrong; every spelling now says it."""
    assert main(["report", "--preset", "paper_example", "--set", f"cam.width_mm={raw}"]) == 2
    assert "is not a number a design may hold" in capsys.readouterr().err


def test_presets_all_load_and_verify():
    from camcore import checks
    from camcore.analysis import analyze

    assert "paper_example" in preset_names()
    for name in preset_names():
        a = analyze(load_preset(name))
        assert a.lift_error <= checks.lift_tolerance(a) and a.valid, name


def test_stl_bytes_roundtrip():
    from camcore import export
    from camcore.analysis import analyze

    a = analyze(load_preset("paper_example"), verify=False)
    mesh = trimesh.load(io.BytesIO(export.stl_bytes(a)), file_type="stl")
    assert mesh.is_watertight


def test_export_of_a_cusped_cam_says_not_to_make_it(tmp_path, capsys):
    """The files are written (exit 1) with the warning on stderr, and in the G-code."""
    out = tmp_path / "cam.nc"
    args = ["export", "--preset", "paper_example", "--follower", "single_concave"]
    args += ["--set", "motion.lift_mm=12", "--set", "motion.rise_deg=65"]
    assert main([*args, "--toolpath", str(out)]) == 1
    err = capsys.readouterr().err
    assert "curvature_convex" in err and "Do not make it as it is" in err
    assert "(WARNING: the design breaks" in out.read_text()


def test_a_design_that_breaks_a_limit_names_it_on_stderr(capsys):
    """The README's exit status: 1 with the broken limits named on stderr, for report
    and compare as for export (a designer's review found report and compare silent
    there: a script saw exit 1 and nothing else)."""
    fast = ["--preset", "paper_example", "--set", "cam.speed_rpm=6000"]  # the spring lets go
    assert main(["report", *fast, "--json"]) == 1
    out, err = capsys.readouterr()
    assert json.loads(out)["valid"] is False
    assert err.startswith("note: the design breaks") and "jump" in err
    assert main(["report", "--preset", "paper_example"]) == 0
    assert capsys.readouterr().err == ""
    assert main(["compare", *fast, "--followers", "single_roller,double_concave"]) == 1
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 2 and all("breaks jump (Eqs. 29-41)" in line for line in err)
    assert err[0].startswith("note: single_roller") and err[1].startswith("note: double_concave")
    rows = run_json(capsys, "compare", "--preset", "paper_example", "--json")
    assert all(r["breaks"] == [] for r in rows)


def test_a_knife_edge_has_no_pitting_life_in_the_endurance_region(capsys):
    """A knife edge has no Hertz stress (unbounded): its pitting life is not estimated,
    not 'endurance (stress within the allowable)' as a designer's review read."""
    assert main(["report", "--preset", "paper_example", "--follower", "knife_edge"]) == 0
    line = next(ln for ln in capsys.readouterr().out.splitlines() if "pitting life" in ln)
    assert "not estimated (knife edge" in line and "endurance" not in line
    assert main(["report", "--preset", "paper_example"]) == 0
    assert "endurance (the stress itself is below the allowable 1000 MPa; the limit " in (
        capsys.readouterr().out
    )


def test_round_off_does_not_show_in_the_text_report(capsys):
    """A designer's review: 'power mean -0.00 W' (a frictionless cam's mean power is 0
    to round-off) and a jump 'at theta = 0-0 deg' (one sample)."""
    from camcore.checks import where_text as _where

    args = ["report", "--preset", "paper_example", "--set", "dynamics.guide_friction=0"]
    assert main(args) == 0
    power = next(ln for ln in capsys.readouterr().out.splitlines() if "power max" in ln)
    assert power.endswith("/ 0.00 W")
    assert _where(((0.0, 0.0), (50.1, 234.9))) == "theta = 0, 50.1-234.9 deg"


def test_notes_for_a_set_that_changes_nothing_and_a_misnamed_file(tmp_path, capsys):
    """A review: e_s set on a double follower changed nothing, and an STL written to
    x.dxf, both without a word."""
    out = tmp_path / "x.dxf"
    args = ["export", "--preset", "paper_example", "--stl", str(out)]
    assert main([*args, "--set", "follower.single_offset_mm=10"]) == 0
    err = capsys.readouterr().err
    assert "--set follower.single_offset_mm: a double concave follower does not use it" in err
    assert f"--stl {out}: written as .stl, whatever its name" in err
    assert main(["export", "--preset", "paper_example", "--stl", str(tmp_path / "c.STL")]) == 0
    assert "whatever its name" not in capsys.readouterr().err


def test_a_cam_that_needs_no_spring_says_so(capsys):
    """A review read 'spring rate min / proposed 0.0 / 0.0 N/m (safety factor 1.5)' as
    a figure left out; the weight keeps this slow cam's follower on it."""
    s = run_json(capsys, "report", "--preset", "classroom_harmonic", "--json")
    assert s["spring_rate_min_N_per_m"] == 0.0 and s["jump_speed_rpm"] > 0
    assert main(["report", "--preset", "classroom_harmonic"]) == 0
    out = capsys.readouterr().out
    assert "none needed at this speed: the follower's weight and any external load keep it" in out
    # its acceleration jumps, accepted by its limits, are said, not passed over
    assert "  ~ acceleration jumps accepted at theta = 0.000, 150.000, 180.000, 330.000" in out


def test_fields_lists_every_settable_field_with_its_default(capsys):
    """A designer's review: nothing listed the fields --set takes. `camcore fields`
    lists each one; every path is one --set accepts, and setting a field to the
    default it lists leaves the default design as it is (the list is the model's)."""
    from camcore.model import Design, design_from_json, field_table, set_field

    rows = run_json(capsys, "fields", "--json")
    assert rows == json.loads(json.dumps(field_table()))
    paths = {r["path"] for r in rows}
    for group in ("cam", "follower", "dynamics", "material", "wear", "limits"):
        model = type(getattr(Design(), group))
        assert {f"{group}.{n}" for n in model.model_fields} <= paths, group
    base = json.loads(Design().model_dump_json())
    for r in rows:
        if r["default"] is None:
            continue
        data = json.loads(json.dumps(base))
        set_field(data, r["path"].replace(".N.", ".0."), r["default"])
        assert design_from_json(json.dumps(data)) == Design(), r["path"]
    roller = next(r for r in rows if r["path"] == "follower.roller_radius_mm")
    assert set(roller["followers"]) == {"single_roller", "double_roller"}
    assert main(["fields"]) == 0
    assert "cam.feed_mm_per_min = 200.0" in capsys.readouterr().out


def test_a_figure_just_under_its_limit_is_not_printed_as_the_limit():
    """A designer's review: a valid pressure angle of 29.999 deg printed "30.00" beside
    the 30 deg limit. Where the usual places would print the limit for another value,
    more are shown."""
    from camcore.report import _fmt_against

    assert _fmt_against(29.9994, 30.0, 2) == "29.999"
    assert _fmt_against(30.0004, 30.0, 2) == "30.0004"
    assert _fmt_against(29.99996, 30.0, 2) == "29.99996"
    assert _fmt_against(30.0, 30.0, 2) == "30.00"
    assert _fmt_against(12.3456, 30.0, 2) == "12.35"
    assert _fmt_against(None, 30.0, 2) == "-" and _fmt_against(29.9994, None, 2) == "30.00"


def test_a_cutter_without_a_toolpath_is_an_error(tmp_path, capsys):
    """--cutter-diameter-mm only sets the toolpath's cutter: alone it had been ignored
    without a word (a maker's review)."""
    out = tmp_path / "cam.stl"
    assert (
        main(
            ["export", "--preset", "paper_example", "--stl", str(out), "--cutter-diameter-mm", "6"]
        )
        == 2
    )
    assert "--cutter-diameter-mm is the cutter of --toolpath FILE" in capsys.readouterr().err
    assert not out.exists()
    nc = tmp_path / "cam.nc"
    args = [
        "export",
        "--preset",
        "paper_example",
        "--toolpath",
        str(nc),
        "--cutter-diameter-mm",
        "6",
    ]
    assert main(args) == 0 and "cutter diameter 6 mm" in nc.read_text()
    js = tmp_path / "design.json"  # a design file keeps it (a review: not ignored there)
    args = ["export", "--preset", "paper_example", "--json", str(js), "--cutter-diameter-mm", "6"]
    assert main(args) == 0 and json.loads(js.read_text())["cam"]["cutter_diameter_mm"] == 6.0


def test_a_defect_of_ours_exits_3_not_1(tmp_path, capsys, monkeypatch):
    """A review: an internal error (a PDF font's IndexError) printed a traceback and
    exited 1, which a script reads as "analysed, breaks a limit"; 2 is bad input. It
    exits 3, saying so after the traceback. And --set's value nested 5000 deep is a
    bare word, not a RecursionError."""
    from camcore import document

    def broken(_a):
        raise IndexError("list index out of range")

    monkeypatch.setattr(document, "pdf_report", broken)
    rc = main(["report", "--preset", "paper_example", "--pdf", str(tmp_path / "r.pdf")])
    err = capsys.readouterr().err
    assert rc == 3 and "Traceback" in err
    assert err.rstrip().endswith(
        "camcore: internal error (IndexError): please report it with the command and the "
        "design file"
    )
    assert main(["report", "--preset", "paper_example", "--set", "name=" + "[" * 5000]) == 2
    assert "RecursionError" not in capsys.readouterr().err


def test_presets_lists_every_shipped_design(capsys):
    """A designer's review: the preset names were only in report's --help."""
    assert main(["presets"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [line.split()[0] for line in lines] == list(preset_names())
    assert any("Section 6 example" in line for line in lines if line.startswith("paper_example"))


def test_extreme_figures_print_in_significant_figures(capsys):
    """A designer's review at 1e-9 rpm read "9802731368133097947136.000000 kg·m²" and
    "jumps at 1009989342029.04 x this speed": beyond report.BIG a figure prints in
    significant figures; ordinary figures keep their decimals."""
    assert main(["report", "--preset", "paper_example", "--set", "cam.speed_rpm=1e-9"]) == 0
    out = capsys.readouterr().out
    assert not re.search(r"\d{9,}", out), out
    assert main(["report", "--preset", "paper_example", "--json"]) == 0
    jump = json.loads(capsys.readouterr().out)["jump_speed_rpm"]  # (not speed-dependent)
    assert "e+21 kg m2" in out and f"jumps at {jump / 1e-9:.3g} x this speed" in out
    assert jump > 1e3  # (so that ratio is past report.BIG)


def test_stations_out_of_order_say_why(capsys):
    """A designer's review: with a high dwell shorter than 4 psi the stations printed
    "0 100 253.871 16.129 170 300" and said nothing; now the line says which station
    comes first and why (Eq. 28, which the violations list too)."""
    args = ["report", "--preset", "paper_example", "--set", "follower.face_radius_mm=-100"]
    main(args)
    line = next(ln for ln in capsys.readouterr().out.splitlines() if "stations  " in ln)
    assert line.endswith(
        "(station 3 before 2: the dwell between them is shorter than 4 psi, Eq. 28)"
    )
    assert main(["report", "--preset", "paper_example"]) == 0
    line = next(ln for ln in capsys.readouterr().out.splitlines() if "stations  " in ln)
    assert line.endswith(" deg")


def test_a_roller_s_wear_and_the_report_s_follower_read_in_words(capsys):
    """A designer's review: a roller's wear row read "0.0000 um ... (sliding up to 0.00
    m/s)", and the HTML report's header "Follower: double_concave"."""
    from camcore.analysis import analyze
    from camcore.document import html_report

    assert main(["report", "--preset", "paper_example", "--follower", "double_roller"]) == 0
    line = next(ln for ln in capsys.readouterr().out.splitlines() if "wear depth max" in ln)
    assert line.endswith("none: a roller rolls (no sliding wear to model)")
    assert main(["report", "--preset", "paper_example"]) == 0
    line = next(ln for ln in capsys.readouterr().out.splitlines() if "wear depth max" in ln)
    assert "um per million cycles (sliding up to" in line
    page = html_report(analyze(load_preset("paper_example"), verify=False))
    assert "<b>Follower:</b> double concave" in page and "double_concave</p>" not in page


def test_python_m_camcore_is_the_camcore_command():
    """``python3 -m camcore`` runs the command line (a review ran it so and got "No
    module named camcore.__main__")."""
    from camcore import package_version

    out = subprocess.run(
        [sys.executable, "-m", "camcore", "--version"], capture_output=True, text=True
    )
    assert out.returncode == 0 and out.stdout.strip() == f"camcore {package_version()}"


def test_a_preset_report_refuses_what_a_file_report_refuses(tmp_path, capsys):
    """A maker's review: `report --preset ... --html same.html --pdf same.html` said
    "wrote same.html" twice (the first a lie: the PDF replaced it), and a report
    named .json went without the note export gives. The checks now hold for a preset
    as for a file."""
    same = str(tmp_path / "same.html")
    base = ["report", "--preset", "paper_example"]
    assert main([*base, "--html", same, "--pdf", same]) == 2
    assert "--html and --pdf name the same file" in capsys.readouterr().err
    assert not (tmp_path / "same.html").exists()  # refused before anything is written
    assert main([*base, "--pdf", str(tmp_path / "r.html")]) == 0
    assert f"--pdf {tmp_path / 'r.html'}: written as .pdf, whatever its name" in (
        capsys.readouterr().err
    )
    assert (tmp_path / "r.html").read_bytes().startswith(b"%PDF")


def test_set_refuses_a_classic_field_beside_a_segment(capsys):
    """A review: `--set motion.rise_deg=90 --set motion.segments.0.angle_deg=80` made
    the classic program and dropped the segment's edit without a word (a sweep's grid
    refused the same mix)."""
    base = ["report", "--preset", "paper_example", "--json"]
    for sets in (
        ["motion.rise_deg=90", "motion.segments.0.angle_deg=80"],
        ["motion.segments.00.law=harmonic", "motion.fall_law=harmonic"],
    ):
        assert main([*base, *(x for s in sets for x in ("--set", s))]) == 2
        err = capsys.readouterr().err
        assert "both set the motion program" in err and "set one of them" in err
    # two classic fields, or two segments, are edits of one program: both kept
    assert main([*base, "--set", "motion.rise_deg=90", "--set", "motion.fall_deg=120"]) == 0
    program = json.loads(capsys.readouterr().out)["stations_deg"]
    high = load_preset("paper_example").motion.high_dwell_deg  # (kept: a classic program)
    assert program[1] == pytest.approx(90.0) and program[-1] == pytest.approx(90.0 + high + 120)


def test_an_empty_follower_list_is_refused(capsys):
    """A review: `--followers ""` ran the default four while `--followers ",,,"` was
    refused as empty."""
    for given in ("", ",,,"):
        assert main(["compare", "--preset", "paper_example", "--followers", given]) == 2
        assert "--followers: unknown (empty)" in capsys.readouterr().err


def test_compare_text_says_unbounded_where_the_report_does(capsys):
    """A README review: compare's table printed a cusp's samples (3019079.610 MPa,
    a pitting life of 1.16e-38 cycles) where `report` says "unbounded" and "none"."""
    args = ["compare", "--preset", "paper_example", "--set", "cam.base_radius_mm=12"]
    assert main(args) == 1
    out = capsys.readouterr().out
    for kind in ("single_concave", "double_concave"):  # the faces that fold back here
        forces = next(ln for ln in out.splitlines() if ln.strip().startswith(kind))
        assert forces.split()[7] == "unbounded", forces  # sigma max
    assert main([*args, "--json"]) == 1
    rows = json.loads(capsys.readouterr().out)
    folded = {r["follower"]: r["unbounded_figures"] for r in rows}
    assert folded["double_concave"] == ["life", "stress", "wear"] and folded["single_roller"] == []
    assert "unbounded" not in next(ln for ln in out.splitlines() if "single_roller" in ln)


@pytest.mark.parametrize(
    "argv, said",
    [
        (["report", "--preset", "paper_example", "--bogus"], "unrecognized arguments: --bogus"),
        (["report", "--preset"], "argument --preset: expected one argument"),
    ],
)
def test_an_unreadable_command_line_names_its_command(argv, said, capsys):
    """README, exit status: an unknown option or a missing value prints the command's
    usage lines, then "camcore CMD: error: ..." (a README review: an unknown option
    had printed the top level's usage and "camcore: error")."""
    with pytest.raises(SystemExit) as stop:
        main(argv)
    err = capsys.readouterr().err
    assert stop.value.code == 2
    assert err.startswith("usage: camcore report ") and f"camcore report: error: {said}" in err
