"""The command line as a hostile or careless user meets it (issue 8): devices and FIFOs,
failed writes, outputs that collide, exit codes, strict JSON, `--set`, presets by name."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from camcore import cli, files
from camcore.model import DesignError, design_from_json, load_preset, preset_names

BREAKS = ["--set", "motion.high_dwell_deg=10"]  # below 4 psi_h: Eq. 28 fails


def run(*args, timeout=60):
    return subprocess.run(
        [sys.executable, "-m", "camcore.cli", *args],
        capture_output=True,
        text=True,
        timeout=timeout,
    )


# --- reading ----------------------------------------------------------------------------


def test_dev_zero_is_refused_at_once():
    proc = run("report", "/dev/zero", timeout=20)
    assert proc.returncode == 2 and "not a regular file" in proc.stderr


def test_fifo_is_refused_without_blocking(tmp_path):
    fifo = tmp_path / "design.json"
    os.mkfifo(fifo)
    proc = run("report", str(fifo), timeout=20)  # would hang forever on a blocking open
    assert proc.returncode == 2 and "not a regular file" in proc.stderr


def test_read_capped_stops_at_the_cap(tmp_path):
    p = tmp_path / "f"
    p.write_bytes(b"x" * 101)
    assert files.read_capped(p, 101) == b"x" * 101
    with pytest.raises(files.FileError, match="101 bytes; the limit is 100"):
        files.read_capped(p, 100)


# --- writing ----------------------------------------------------------------------------


def test_failed_write_leaves_the_old_file(tmp_path, monkeypatch):
    target = tmp_path / "cam.stl"
    target.write_bytes(b"good old part")
    real_fsync = os.fsync

    def disk_full(fd):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "fsync", disk_full)
    with pytest.raises(files.FileError, match="No space left"):
        files.write_atomic(target, b"new" * 1000)
    monkeypatch.setattr(os, "fsync", real_fsync)
    assert target.read_bytes() == b"good old part"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cam.stl"]  # no temp file left


def test_disk_full_through_the_cli(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(os, "fsync", lambda fd: (_ for _ in ()).throw(OSError(28, "No space")))
    out = tmp_path / "cam.stl"
    assert cli.main(["export", "--preset", "paper_example", "--stl", str(out)]) == 2
    assert "No space" in capsys.readouterr().err and not out.exists()


def test_one_unwritable_output_leaves_every_file_as_it_was(tmp_path, capsys):
    """All or none across the files of one export (a maker's review found the STL of
    one cam replaced beside the CSV of another after an exit 2): the DXF's directory is
    missing, so neither the STL before it nor the CSV after it is touched."""
    stl, csv = tmp_path / "cam.stl", tmp_path / "cam.csv"
    stl.write_bytes(b"the old cam's STL")
    csv.write_bytes(b"the old cam's profile")
    args = ["export", "--preset", "paper_example", "--stl", str(stl)]
    args += ["--dxf", str(tmp_path / "typo" / "cam.dxf"), "--csv", str(csv)]
    assert cli.main(args) == 2
    err = capsys.readouterr().err
    assert "typo" in err and "wrote" not in err
    assert stl.read_bytes() == b"the old cam's STL" and csv.read_bytes() == b"the old cam's profile"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cam.csv", "cam.stl"]  # no temp file
    (tmp_path / "typo").mkdir()
    assert cli.main(args) == 0 and stl.read_bytes().startswith(b"camdesigner ")


def test_a_rename_that_fails_midway_gives_the_replaced_files_back(tmp_path, monkeypatch):
    """All or none when the second rename fails after the first succeeded (a target
    another user owns in a sticky directory; found by a review): the STL already
    replaced gets its old contents back, a new file where none was is removed, and no
    temporary file or kept link is left."""
    stl, csv, dxf = tmp_path / "cam.stl", tmp_path / "cam.csv", tmp_path / "cam.dxf"
    stl.write_bytes(b"old stl")
    csv.write_bytes(b"old csv")
    real = os.replace

    def refuse_the_csv(src, dst):
        if Path(dst) == csv:
            raise PermissionError(1, "Operation not permitted")
        return real(src, dst)

    monkeypatch.setattr(os, "replace", refuse_the_csv)
    args = ["export", "--preset", "paper_example", "--dxf", str(dxf), "--stl", str(stl)]
    assert cli.main([*args, "--csv", str(csv)]) == 2
    monkeypatch.undo()
    assert stl.read_bytes() == b"old stl" and csv.read_bytes() == b"old csv"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cam.csv", "cam.stl"]


def test_same_output_twice_is_refused(tmp_path):
    out = tmp_path / "cam.out"
    proc = run(
        "export",
        "--preset",
        "paper_example",
        "--stl",
        str(out),
        "--dxf",
        str(tmp_path / "." / "cam.out"),
    )
    assert proc.returncode == 2 and "same file" in proc.stderr and not out.exists()


def test_output_over_the_input_is_refused(tmp_path):
    src = tmp_path / "d.json"
    src.write_text(load_preset("paper_example").model_dump_json())
    before = src.read_bytes()
    proc = run("export", str(src), "--stl", str(src))
    assert proc.returncode == 2 and "input design file" in proc.stderr
    assert src.read_bytes() == before


# --- exit codes -------------------------------------------------------------------------


@pytest.mark.parametrize("command", [["report"], ["report", "--json"], ["compare"]])
def test_exit_codes(command):
    assert run(*command, "--preset", "paper_example").returncode == 0
    proc = run(*command, "--preset", "paper_example", *BREAKS)
    assert proc.returncode == 1, proc.stderr
    assert proc.stdout  # the report is still printed
    if "--json" in command:
        assert json.loads(proc.stdout)["violations"][0]["code"] == "high_dwell_arc"


def test_export_of_a_design_that_breaks_a_limit_writes_and_exits_1(tmp_path):
    out = tmp_path / "cam.dxf"
    proc = run("export", "--preset", "paper_example", *BREAKS, "--dxf", str(out))
    assert proc.returncode == 1 and out.stat().st_size > 0
    assert "high_dwell_arc" in proc.stderr
    assert "sharp corner" not in proc.stderr  # that limit leaves the profile smooth


def test_an_undercut_export_says_the_part_has_a_sharp_corner(tmp_path):
    """A slightly undercut roller cam is still star-shaped and is written (exit 1), but
    its profile has a corner where the roller's path is only touched (a maker's review
    measured an 11.45 deg turn at one vertex): the CLI says not to make it."""
    out = tmp_path / "cam.stl"
    undercut = ["--follower", "single_roller", "--set", "cam.base_radius_mm=23.5"]
    undercut += ["--set", "follower.roller_radius_mm=11.5", "--set", "motion.rise_deg=40"]
    undercut += ["--set", "motion.high_dwell_deg=130"]
    proc = run("export", "--preset", "paper_example", *undercut, "--stl", str(out))
    assert proc.returncode == 1 and out.stat().st_size > 0
    assert "roller_undercut" in proc.stderr and "sharp corner" in proc.stderr


def test_version():
    proc = run("--version")
    assert proc.returncode == 0 and proc.stdout.startswith("camcore ")


# --- --set and --tolerance-mm -----------------------------------------------------------


def test_set_overrides_fields(capsys):
    assert (
        cli.main(
            [
                "report",
                "--preset",
                "paper_example",
                "--json",
                "--set",
                "cam.base_radius_mm=90",
                "--set",
                "follower.kind=double_roller",
            ]
        )
        == 0
    )
    s = json.loads(capsys.readouterr().out)
    assert s["follower"] == "double_roller"
    assert s["dwell_radius_mm"] == pytest.approx(
        json.loads(
            run(
                "report",
                "--preset",
                "paper_example",
                "--json",
                "--follower",
                "double_roller",
                "--set",
                "cam.base_radius_mm=90",
            ).stdout
        )["dwell_radius_mm"]
    )


@pytest.mark.parametrize(
    "assignment, message",
    [
        ("cam.base_radius=90", "no such field"),
        ("cam.base_radius_mm=true", "cam.base_radius_mm"),
        ('cam.base_radius_mm="90"', "cam.base_radius_mm"),
        ("cam.base_radius_mm.x=1", "not a group"),
        ("nonsense", "FIELD.PATH=VALUE"),
        # an index is ASCII digits: "²" passed str.isdigit and crashed int() (a review)
        ("motion.segments.².angle_deg=1", "is not an index of motion.segments, a list of 4"),
        ("motion.segments.9.angle_deg=1", "'9' is not an index of motion.segments, a list"),
        ("motion.segments." + "9" * 5000 + ".angle_deg=1", "'99999999999999999999…' is not"),
    ],
)
def test_set_errors_name_the_field(assignment, message):
    proc = run("report", "--preset", "paper_example", "--set", assignment)
    assert proc.returncode == 2 and message in proc.stderr, proc.stderr


def test_an_empty_name_or_a_huge_number_is_refused_in_words(tmp_path):
    """A CLI review: ``--stl ""`` beside ``--dxf`` was dropped without a word, as was
    ``--preset ""`` beside a design file, and a 5000-digit number answered with Python's
    advice (sys.set_int_max_str_digits)."""
    dxf = tmp_path / "a.dxf"
    proc = run("export", "--preset", "paper_example", "--stl", "", "--dxf", str(dxf))
    assert proc.returncode == 2 and "--stl: an empty file name" in proc.stderr
    assert not dxf.exists()
    design = tmp_path / "d.json"
    design.write_text('{"cam": {"base_radius_mm": 70}}')
    proc = run("report", str(design), "--preset", "")
    assert proc.returncode == 2 and "not both" in proc.stderr
    design.write_text('{"cam": {"base_radius_mm": ' + "1" * 5000 + "}}")
    proc = run("report", str(design))
    assert proc.returncode == 2 and "more than 4300 digits" in proc.stderr
    assert "set_int_max_str_digits" not in proc.stderr


def test_tolerance_option_is_met(tmp_path, capsys):
    out = tmp_path / "p.csv"
    coarse = ["export", "--preset", "paper_example", "--set", "limits.resolution_deg=5"]
    assert cli.main([*coarse, "--csv", str(out), "--tolerance-mm", "0.05"]) == 0
    n_coarse = len(out.read_text().splitlines())
    assert cli.main([*coarse, "--csv", str(out), "--tolerance-mm", "0.0001"]) == 0
    n_fine = len(out.read_text().splitlines())
    assert n_fine > 3 * n_coarse  # the chordal bound drives the vertex count
    assert cli.main([*coarse, "--csv", str(out), "--tolerance-mm", "5"]) == 2
    assert "export_tolerance_mm" in capsys.readouterr().err


# --- strict JSON ------------------------------------------------------------------------


def _paper() -> dict:
    """The paper example as its format 1 file (classic motion keys)."""
    from importlib.resources import files as res

    return json.loads(res("camcore.presets").joinpath("paper_example.json").read_text())


@pytest.mark.parametrize(
    "edit, field",
    [
        (
            lambda t: t.replace('"lift_mm": 15.0', '"lift_mm": 15.0, "lift_mm": 99'),
            "motion.lift_mm",
        ),
        (lambda t: t.replace('"lift_mm": 15.0', '"lift_mm": true'), "motion.lift_mm"),
        (lambda t: t.replace('"lift_mm": 15.0', '"lift_mm": "15"'), "motion.lift_mm"),
        (lambda t: t.replace('"lift_mm": 15.0', '"lift_mm": NaN'), "motion.lift_mm"),
        (lambda t: t.replace('"lift_mm": 15.0', '"lift_mm": -Infinity'), "motion.lift_mm"),
        (lambda t: t.replace('"lift_mm": 15.0', '"lift_mm": [[[[[[[[[1]]]]]]]]]'), "nested deeper"),
    ],
)
def test_loose_json_is_refused_naming_the_field(edit, field):
    text = edit(json.dumps(_paper()))
    with pytest.raises(DesignError, match=field.replace(".", r"(\.|: )")):
        design_from_json(text)


def test_integers_still_count_as_numbers():
    d = _paper()
    d["cam"]["base_radius_mm"] = 80
    assert design_from_json(json.dumps(d)).cam.base_radius_mm == 80.0


# --- presets by name --------------------------------------------------------------------


@pytest.mark.parametrize(
    "name",
    ["../../x", "/tmp/x", "paper_example.json", "..", "paper_example/../paper_example", "", "\x00"],
)
def test_preset_names_are_a_fixed_set(name, tmp_path):
    (tmp_path / "x.json").write_text(json.dumps(_paper()))
    with pytest.raises(DesignError, match="no preset"):
        load_preset(name)


def test_presets_are_package_data():
    from importlib.resources import files as res

    assert "paper_example" in preset_names()
    assert res("camcore.presets").joinpath("paper_example.json").is_file()
    assert not (Path(__file__).parents[1] / "static" / "presets").exists()


def test_concurrent_reads_do_not_interfere(tmp_path):
    """read_capped holds no shared state: threads reading at once all get their bytes."""
    paths = []
    for i in range(8):
        p = tmp_path / f"{i}.json"
        p.write_bytes(bytes([65 + i]) * (1000 + i))
        paths.append(p)
    got = {}
    threads = [
        threading.Thread(target=lambda p=p: got.__setitem__(p, files.read_capped(p, 2000)))
        for p in paths
    ]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert all(got[p] == p.read_bytes() for p in paths)


# --- the printable report -----------------------------------------------------------------


def test_html_and_pdf_report(tmp_path):
    """`report --html/--pdf`: a self-contained page (inline SVG plots: curves, profile,
    stations; no external
    reference) with the key numbers and the violations, the design name escaped; a PDF
    that starts like one. stdout stays pure JSON with --json."""
    d = json.loads(load_preset("paper_example").model_dump_json())
    d["name"] = "<b id=inj>x</b> & co"
    d["motion"]["high_dwell_deg"] = 10  # breaks Eq. 28
    src = tmp_path / "d.json"
    src.write_text(json.dumps(d))
    page, pdf = tmp_path / "r.html", tmp_path / "r.pdf"
    proc = run("report", str(src), "--json", "--html", str(page), "--pdf", str(pdf))
    assert proc.returncode == 1, proc.stderr
    assert json.loads(proc.stdout)["valid"] is False
    text = page.read_text()
    assert "<b id=inj>" not in text and "&lt;b id=inj&gt;x&lt;/b&gt; &amp; co" in text
    assert text.count("<svg") == 3 and "Eq. 28" in text and "high_dwell_arc" in text
    for external in ("<link", "<script", "<img", "src=", 'href="http', "url(http"):
        assert external not in text  # nothing to fetch: XML namespaces only
    assert "Hertz contact stress" in text and "Jerk" in text
    # the inputs, the program segment by segment (a teacher's own program had not
    # been named in its report)
    assert "<h2>Inputs</h2>" in text
    assert "1. rise 100 deg 15 mm cycloidal; 2. dwell 10 deg; 3. fall 130 deg" in text
    assert pdf.read_bytes().startswith(b"%PDF") and pdf.stat().st_size > 10_000
    # every page A4 (595.28 x 841.89 pt), a wide one turned: the plot pages had been
    # 11 x 9.6 in and 5 x 5 in, printed at whatever scale the printer chose
    import re

    boxes = re.findall(rb"/MediaBox \[ *0 0 ([\d.]+) ([\d.]+) *\]", pdf.read_bytes())
    assert len(boxes) == 4
    for w, h in boxes:
        assert sorted((float(w), float(h))) == pytest.approx([595.44, 841.68], abs=0.5)
    proc = run("report", str(src), "--html", str(src))
    assert proc.returncode == 2 and "input design file" in proc.stderr


def test_the_html_report_says_what_a_valid_design_accepts(tmp_path):
    """A review: the page said 'All limits met.' of a design whose limits accept its
    acceleration jumps, without a word about them."""
    page = tmp_path / "r.html"
    proc = run("report", "--preset", "classroom_harmonic", "--html", str(page))
    assert proc.returncode == 0, proc.stderr
    text = page.read_text()
    assert "All limits met." in text
    assert "acceleration jumps accepted at theta = 0.000, 150.000" in text


def test_the_report_plots_draw_the_limits():
    """A designer's review: the report's pressure-angle and stress plots had no limit
    lines, where the app's curves draw them; a design over its stress limit read as
    sound there."""
    from camcore.analysis import analyze
    from camcore.document import _figure
    from camcore.model import load_preset

    a = analyze(load_preset("paper_example"), verify=False)
    fig = _figure(a)
    by_title = {ax.get_title(): ax for ax in fig.axes if ax.get_visible()}
    phi = a.design.limits.max_pressure_angle_deg
    levels = sorted(
        ln.get_ydata()[0]
        for ln in by_title["Pressure angle (Eqs. 5, 13)"].lines
        if ln.get_linestyle() == "--"
    )
    assert levels == [-phi, phi]
    (stress,) = [
        ln for ln in by_title["Hertz contact stress (Eq. 42)"].lines if ln.get_linestyle() == "--"
    ]
    limit = a.design.limits
    from camcore.model import allowable_contact_stress_MPa

    expected = allowable_contact_stress_MPa(a.design) / limit.contact_stress_safety_factor
    assert stress.get_ydata()[0] == pytest.approx(expected)
    knife = _figure(analyze(load_preset("paper_example").with_kind("knife_edge"), verify=False))
    titled = {ax.get_title(): ax for ax in knife.axes}
    assert not [
        ln for ln in titled["Hertz contact stress (Eq. 42)"].lines if ln.get_linestyle() == "--"
    ]
