"""Design-space sweeps (issue 12): rows equal the single reports, invalid combinations
become rows that say why, an interrupted run resumes without recomputing, and the same
work runs on a Dask LocalCluster."""

from __future__ import annotations

import json
import math
import os
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

from camcore import sweep
from camcore.files import FileError
from camcore.model import DesignError

SPEC = {
    "base": {"preset": "paper_example"},
    "grid": {
        "cam.base_radius_mm": {"from": 70, "to": 90, "num": 3},
        "follower.kind": ["single_roller", "double_concave"],
    },
}


def rows_of(path) -> list[dict]:
    return pq.read_table(path).to_pylist()


def test_rows_equal_single_reports(tmp_path):
    spec = sweep.parse_spec(json.dumps(SPEC))
    assert spec.size == 6
    assert [spec.point(i) for i in range(6)] == list(spec.points())
    assert spec.chunk(1, 4) == list(spec.points())[4:]
    n = sweep.run(spec, tmp_path / "r.parquet", chunk=4, progress=None)
    rows = rows_of(tmp_path / "r.parquet")
    assert n == len(rows) == 6
    assert [(r["grid.cam.base_radius_mm"], r["grid.follower.kind"]) for r in rows] == [
        (70.0, "single_roller"),
        (70.0, "double_concave"),
        (80.0, "single_roller"),
        (80.0, "double_concave"),
        (90.0, "single_roller"),
        (90.0, "double_concave"),
    ]
    for r in (rows[1], rows[4]):  # through the real command line
        out = subprocess.run(
            [
                sys.executable,
                "-m",
                "camcore.cli",
                "report",
                "--preset",
                "paper_example",
                "--json",
                "--set",
                f"cam.base_radius_mm={r['grid.cam.base_radius_mm']}",
                "--set",
                f"follower.kind={r['grid.follower.kind']}",
            ],
            capture_output=True,
            text=True,
        )
        single = sweep.flatten(json.loads(out.stdout))
        for key, value in single.items():
            assert r[key] == value, key
        assert r["error"] is None


def test_an_invalid_combination_is_a_row_that_says_why(tmp_path):
    spec = sweep.parse_spec(
        json.dumps(
            {"base": {"preset": "paper_example"}, "grid": {"cam.bore_diameter_mm": [20, 500]}}
        )
    )
    sweep.run(spec, tmp_path / "r.parquet", progress=None)
    ok, bad = rows_of(tmp_path / "r.parquet")
    assert ok["valid"] is True and ok["error"] is None
    assert bad["valid"] is False and "bore_diameter_mm" in bad["error"]


def test_an_interrupted_sweep_resumes_without_recomputing(tmp_path, monkeypatch):
    spec = sweep.parse_spec(json.dumps(SPEC))
    out = tmp_path / "r.parquet"

    def stop_after_two(done, total, t0):
        if done >= 4:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        sweep.run(spec, out, chunk=2, progress=stop_after_two)
    assert not out.exists() and len(list((tmp_path / "r.parquet.parts").glob("*.parquet"))) == 2
    calls = []
    real = sweep.run_chunk
    monkeypatch.setattr(sweep, "run_chunk", lambda *a: calls.append(a[1]) or real(*a))
    sweep.run(spec, out, chunk=2, progress=None)
    assert sum(len(c) for c in calls) == 2  # only the missing chunk
    # a kept chunk damaged since (not by this program: it writes atomically) is redone
    _interrupted(spec, out, 2)
    (tmp_path / "r.parquet.parts" / "chunk-000000.parquet").write_bytes(b"not parquet")
    calls.clear()
    sweep.run(spec, out, chunk=2, progress=None)
    assert calls == [spec.chunk(0, 2), spec.chunk(2, 2)]
    fresh = tmp_path / "fresh.parquet"
    monkeypatch.setattr(sweep, "run_chunk", real)
    sweep.run(spec, fresh, chunk=3, progress=None)
    assert rows_of(out) == rows_of(fresh)
    assert not (tmp_path / "r.parquet.parts").exists()


def test_a_run_that_keeps_nothing_leaves_no_parts(tmp_path, monkeypatch, capsys):
    """A scheduler that cannot be reached, or Ctrl-C before the first chunk is done,
    leaves no OUT.parts/ behind (it had left one holding only its label), and the
    terminal is not told of a resume with nothing to resume."""
    spec = sweep.parse_spec(json.dumps(SPEC))
    out = tmp_path / "r.parquet"
    with pytest.raises(DesignError, match="--scheduler nonsense"):
        sweep.run(spec, out, scheduler="nonsense", progress=None)
    assert list(tmp_path.iterdir()) == []

    def stopped(*args):
        raise KeyboardInterrupt

    monkeypatch.setattr(sweep, "run_chunk", stopped)
    with pytest.raises(KeyboardInterrupt):
        sweep.run(spec, out, chunk=2, progress=lambda *a: None)
    assert list(tmp_path.iterdir()) == []
    assert "interrupted before a chunk was finished: nothing kept" in capsys.readouterr().err


def _interrupted(spec, out, chunk: int, **how) -> None:
    """Run until two chunks are kept, then stop as Ctrl-C would."""

    def stop(done, total, rate):
        if done >= 2 * chunk:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        sweep.run(spec, out, chunk=chunk, progress=stop, **how)


def test_parts_of_another_sweep_are_not_mixed_in(tmp_path, monkeypatch):
    """Finished chunks are reused only by the same spec, mode, chunk size and camcore
    code (a resume with another --chunk had written 32 rows of 60, or 88 with repeats;
    one in another checkout of the same version would have mixed two codes' rows);
    parts with no chunk yet are taken over."""
    spec = sweep.parse_spec(json.dumps(SPEC))
    out = tmp_path / "r.parquet"
    _interrupted(spec, out, 2, verify=False)
    with pytest.raises(DesignError, match=r"chunk 2 \(this run: 3\)"):
        sweep.run(spec, out, chunk=3, verify=False, progress=None)
    with pytest.raises(DesignError, match=r"mode 'no-verify' \(this run: 'fast'\)"):
        sweep.run(spec, out, chunk=2, fast=True, progress=None)
    # another checkout (or an edited install) of the same version: its code differs
    monkeypatch.setattr(sweep, "code_fingerprint", lambda: "0123456789abcdef")
    with pytest.raises(DesignError, match=r"code '[0-9a-f]{16}' \(this run: '0123456789abcdef'\)"):
        sweep.run(spec, out, chunk=2, verify=False, progress=None)
    monkeypatch.undo()
    other = sweep.parse_spec(json.dumps({"grid": {"cam.base_radius_mm": [70, 80]}}))
    with pytest.raises(DesignError, match="another sweep: spec"):
        sweep.run(other, out, chunk=2, verify=False, progress=None)
    assert sweep.run(spec, out, chunk=2, verify=False, progress=None) == spec.size
    fresh = tmp_path / "fresh.parquet"
    sweep.run(spec, fresh, chunk=4, verify=False, progress=None)
    assert rows_of(out) == rows_of(fresh)
    import pyarrow.parquet as pq

    from camcore import code_fingerprint

    meta = pq.read_schema(fresh).metadata  # the table says which code made it
    assert meta[sweep.CODE_METADATA.encode()] == code_fingerprint().encode()
    empty = tmp_path / "e.parquet.parts"  # e.g. a run stopped before its first chunk
    empty.mkdir()
    (empty / "sweep.json").write_text("{}")
    assert sweep.run(other, tmp_path / "e.parquet", verify=False, progress=None) == 2


def test_a_kept_chunk_must_be_this_runs_own_and_whole(tmp_path, monkeypatch):
    """A review: a chunk of another sweep put among a run's parts was joined in (its
    rows then named other designs than the spec's, and ``pareto --design`` printed a
    cam other than the row listed), one of too few rows shifted every later row, and a
    damaged chunk whose footer still read failed the join on every run (exit 3). Each
    chunk now carries its run's stamp and number, and reads back whole, or is redone."""
    spec = sweep.parse_spec(json.dumps(SPEC))
    other = sweep.parse_spec(json.dumps({"grid": {"cam.base_radius_mm": [40, 50, 60, 65]}}))
    out, theirs = tmp_path / "r.parquet", tmp_path / "o.parquet"
    _interrupted(other, theirs, 2, verify=False)
    _interrupted(spec, out, 2, verify=False)
    parts = tmp_path / "r.parquet.parts"
    foreign = (tmp_path / "o.parquet.parts" / "chunk-000001.parquet").read_bytes()
    (parts / "chunk-000002.parquet").write_bytes(foreign)  # of the same size, not ours
    good = (parts / "chunk-000000.parquet").read_bytes()
    (parts / "chunk-000001.parquet").write_bytes(good)  # ours, but chunk 0's
    calls = []
    real = sweep.run_chunk
    monkeypatch.setattr(sweep, "run_chunk", lambda *a: calls.append(a[1]) or real(*a))
    assert sweep.run(spec, out, chunk=2, verify=False, progress=None) == spec.size
    assert calls == [spec.chunk(1, 2), spec.chunk(2, 2)]
    grid = [(r["grid.cam.base_radius_mm"], r["grid.follower.kind"]) for r in rows_of(out)]
    assert grid == [tuple(p.values()) for p in spec.points()]
    # a chunk whose footer reads but whose data does not (a byte flipped mid-file)
    _interrupted(spec, out, 2, verify=False)
    first = parts / "chunk-000000.parquet"
    data = bytearray(first.read_bytes())
    middle = len(data) // 3
    data[middle : middle + 64] = bytes(64)
    first.write_bytes(bytes(data))
    calls.clear()
    assert sweep.run(spec, out, chunk=2, verify=False, progress=None) == spec.size
    assert spec.chunk(0, 2) in calls


def test_a_table_whose_rows_are_not_its_specs_names_no_design(tmp_path):
    """design_of_row checks the row's grid values against its spec's point: a table
    whose rows were reordered or mixed gives no design rather than another one."""
    import pyarrow as pa

    spec = sweep.parse_spec(json.dumps(SPEC))
    out = tmp_path / "r.parquet"
    sweep.run(spec, out, verify=False, progress=None)
    assert sweep.design_of_row(out, 3).cam.base_radius_mm == 80.0
    table = pq.read_table(out)
    swapped = pa.concat_tables([table.slice(3, 1), table.slice(0, 3), table.slice(4)])
    pq.write_table(swapped.replace_schema_metadata(table.schema.metadata), out)
    with pytest.raises(FileError, match="row 3 holds .* the rows are not the spec's"):
        sweep.design_of_row(out, 3)


def test_the_parts_folder_holds_only_the_sweeps_own_files(tmp_path):
    """A review: an existing OUT.parts/ was taken over and removed with everything in
    it (a user's notes and the spec itself), and a linked one failed after the table was
    written (exit 3). A folder of other files, or a link, is refused before any work;
    the run removes only its own files."""
    spec = sweep.parse_spec(json.dumps(SPEC))
    out = tmp_path / "r.parquet"
    parts = tmp_path / "r.parquet.parts"
    parts.mkdir()
    (parts / "notes.txt").write_text("mine")
    with pytest.raises(FileError, match=r"holds files that are not a sweep's \(notes.txt\)"):
        sweep.run(spec, out, verify=False, progress=None)
    assert (parts / "notes.txt").read_text() == "mine"
    (parts / "notes.txt").unlink()
    parts.rmdir()
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    parts.symlink_to(elsewhere)
    with pytest.raises(FileError, match="a link or a file"):
        sweep.run(spec, out, verify=False, progress=None)
    assert not out.exists() and list(elsewhere.iterdir()) == []
    parts.unlink()
    # a link inside it, even under a sweep's own name, is written through by a run (a
    # review: a victim file became the label), and a file of the user's that looks
    # like a temporary one is the user's
    parts.mkdir()
    victim = tmp_path / "elsewhere" / "victim.json"
    victim.write_text("mine")
    (parts / "sweep.json").symlink_to(victim)
    with pytest.raises(FileError, match=r"not a sweep's \(sweep.json\)"):
        sweep.run(spec, out, verify=False, progress=None)
    assert victim.read_text() == "mine"
    (parts / "sweep.json").unlink()
    (parts / ".my draft.tmp").write_text("mine")
    with pytest.raises(FileError, match=r"not a sweep's \(.my draft.tmp\)"):
        sweep.run(spec, out, verify=False, progress=None)
    (parts / ".my draft.tmp").unlink()
    assert sweep.run(spec, out, verify=False, progress=None) == spec.size
    assert sorted(p.name for p in tmp_path.iterdir()) == ["elsewhere", "r.parquet"]


def test_a_bad_output_fails_before_any_work(tmp_path, monkeypatch):
    spec = sweep.parse_spec(json.dumps(SPEC))
    monkeypatch.setattr(sweep, "run_chunk", lambda *a: pytest.fail("computed"))
    monkeypatch.setattr(sweep, "_cluster", lambda *a: pytest.fail("a cluster started"))
    with pytest.raises(FileError, match="no directory"):
        sweep.run(spec, tmp_path / "missing" / "r.parquet", workers=2, progress=None)
    with pytest.raises(FileError, match="is a directory"):
        sweep.run(spec, tmp_path, progress=None)
    with pytest.raises(FileError, match="no directory"):
        sweep.run(spec, tmp_path / "missing" / "r.parquet", progress=None)
    assert not (tmp_path / "missing").exists()
    # a CLI review: a FIFO, a device or a link into a missing folder was refused only
    # after the whole grid ran, and left OUT.parts/ behind (/dev/null.parts/ as root)
    os.mkfifo(tmp_path / "pipe.parquet")
    (tmp_path / "dangling.parquet").symlink_to("nowhere/r.parquet")
    for out, message in [
        (tmp_path / "pipe.parquet", "not a regular file"),
        (Path("/dev/null"), "under /dev or /proc"),
        (tmp_path / "dangling.parquet", "no directory"),
    ]:
        with pytest.raises(FileError, match=message):
            sweep.run(spec, out, progress=None)
        assert not out.with_name(out.name + ".parts").exists()


def test_pareto_refuses_a_fifo_and_an_infinite_figure_is_no_figure(pareto_table, tmp_path):
    """A CLI review: ``pareto`` on a FIFO hung in pyarrow; in a hand-edited table a
    roller's -inf stress was its follower's "least" (and --json printed -Infinity, not
    JSON), while the front left it out, blamed on knife edges."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    from camcore.explore import table_front

    os.mkfifo(tmp_path / "pipe.parquet")
    with pytest.raises(FileError, match="not a regular file"):
        table_front(tmp_path / "pipe.parquet", ["stress", "cam_size"])
    with pytest.raises(FileError, match="not a regular file"):
        sweep.design_of_row(tmp_path / "pipe.parquet", 0)
    t = pq.read_table(pareto_table)
    valid = np.asarray(t.column("valid").to_pylist(), dtype=bool)
    rollers = np.asarray(t.column("grid.follower.kind").to_pylist()) == "single_roller"
    [i, j] = np.flatnonzero(valid & rollers)[:2]
    stress = np.array(t.column("contact_stress_max_MPa.cycle").to_pylist(), dtype=float)
    stress[i], stress[j] = -np.inf, np.inf
    k = t.column_names.index("contact_stress_max_MPa.cycle")
    edited = tmp_path / "edited.parquet"
    pq.write_table(t.set_column(k, "contact_stress_max_MPa.cycle", pa.array(stress)), edited)
    f = table_front(edited, ["stress", "cam_size"])
    assert np.isfinite(f.least["single_roller"]["value"])
    assert f.least["single_roller"]["row"] not in (i, j)
    assert f.lacking_by == {"stress": 2} and f.lacking_why == ["2 rows hold an infinite stress"]
    js = subprocess.run(
        [sys.executable, "-m", "camcore.cli", "pareto", str(edited), "--json"],
        capture_output=True,
        text=True,
    )
    assert js.returncode == 0 and "Infinity" not in js.stdout
    json.loads(js.stdout)
    # ... and an infinite grid value is null in the JSON (a review: it crashed, exit 3)
    k = t.column_names.index("grid.cam.base_radius_mm")
    radii = np.full(t.num_rows, np.inf)
    pq.write_table(t.set_column(k, "grid.cam.base_radius_mm", pa.array(radii)), edited)
    js = subprocess.run(
        [sys.executable, "-m", "camcore.cli", "pareto", str(edited), "--json"],
        capture_output=True,
        text=True,
    )
    assert js.returncode == 0, js.stderr
    assert json.loads(js.stdout)["front"][0]["grid"]["cam.base_radius_mm"] is None
    knives = tmp_path / "knives.parquet"
    grid = {"follower.kind": ["knife_edge", "single_roller"], "cam.base_radius_mm": [70]}
    spec = sweep.parse_spec(json.dumps({"grid": grid}))
    sweep.run(spec, knives, verify=False, progress=None)
    f = table_front(knives, ["stress", "cam_size"])
    assert f.lacking_by == {"stress": 1} and f.lacking_why == ["a knife edge has no contact stress"]


@pytest.mark.parametrize(
    "spec, message",
    [
        ({"grid": {"cam.nope": [1]}}, "cam.nope: no such field"),
        ({"grid": {"cam.base_radius_mm": {"from": 1, "to": 2}}}, "a range is"),
        ({"grid": {"cam.base_radius_mm": {"from": 1, "to": 2, "num": 0}}}, "num"),
        ({"grid": {"cam.base_radius_mm": []}}, "a list of 1"),
        ({"grid": {"cam.base_radius_mm": [1]}, "extra": 1}, "an object with"),
        ({"base": {"preset": "../../etc/passwd"}, "grid": {"cam.width_mm": [1]}}, "no preset"),
        ({"grid": {"follower.kind": ["single_roller", 5]}}, "one type.*number and text"),
        ({"grid": {"cam.base_radius_mm": [70, True]}}, "one type.*boolean and number"),
        ({"grid": {"cam.base_radius_mm": ["80", "90"]}}, r'"80" is not a value of this'),
        ({"grid": {"follower.kind": ["double_roler"]}}, '"double_roler" is not a value'),
        ({"grid": {"follower.kind": {"from": 1, "to": 2, "num": 2}}}, "1.0 is not a value"),
        (
            {"grid": {"cam.base_radius_mm": [70], "cam": [{"base_radius_mm": 90}]}},
            "grid.cam and grid.cam.base_radius_mm: one sets a part of the other",
        ),
        # one field twice (a review: the later path won while the first's column stayed)
        (
            {"grid": {"motion.segments.0.law": ["poly_345"], "motion.rise_law": ["cycloidal"]}},
            "both set the motion program",
        ),
        (
            {"grid": {"motion.rise_deg": [100], "motion.segments.0.angle_deg": [90]}},
            "both set the motion program",
        ),
        (
            {"grid": {"motion.segments.0.law": ["poly_345"], "motion.segments.00.law": ["x"]}},
            "segments.0.law and grid.motion.segments.00.law: both set one field",
        ),
        # true is no number, for every row (not a row each that says so)
        ({"grid": {"cam.base_radius_mm": [True, False]}}, "true is not a value of this field"),
        ({"grid": {"motion.rise_deg": [True, False]}}, "true is not a value of this field"),
        ({"grid": {"motion.lift_mm": ["5"]}}, '"5" is not a value of this field'),
        # a classic field of a program of other segments: no row could take it
        (
            {"base": {"preset": "double_index"}, "grid": {"motion.lift_mm": [5, 6]}},
            "5 is not a value of this field: .*edit motion.segments",
        ),
        ({"grid": {"cam." + "1" * 5000: [1]}}, "no such field"),  # (int() of 5000 digits)
        (
            {"grid": {"cam.base_radius_mm": {"from": -1.7e308, "to": 1.7e308, "num": 3}}},
            "span more than a float holds",
        ),
        # an inline base's keys are the base's
        ({"base": {"preset": "paper_example", "x": 1}, "grid": {"cam.width_mm": [9]}}, "^base: "),
        # a value twice, or a range that drops its end (a review: both ran unsaid)
        (
            {"grid": {"cam.base_radius_mm": {"from": 60, "to": 110, "num": 1}}},
            r"num 1 gives only from = 60, not to = 110",
        ),
        (
            {"grid": {"cam.base_radius_mm": {"from": 60, "to": 60, "num": 3}}},
            "the value 60.0 comes twice; each value once; a range's from and to must differ",
        ),
        ({"grid": {"cam.base_radius_mm": [60, 70, 60.0]}}, "the value 60.0 comes twice"),
        ({"grid": {"follower.kind": ["knife_edge", "knife_edge"]}}, "'knife_edge' comes twice"),
        # (a review: a range of it wrote a table of non-designs)
        ({"grid": {"schema_version": {"from": 1, "to": 3, "num": 3}}}, "format, not a param"),
        (
            {
                "grid": {
                    "cam.base_radius_mm": {"from": 60, "to": 90, "num": 1001},
                    "cam.width_mm": {"from": 5, "to": 20, "num": 1000},
                }
            },
            "at most",
        ),
    ],
)
def test_bad_specs_are_refused_with_the_key_named(spec, message):
    with pytest.raises(DesignError, match=message):
        sweep.parse_spec(json.dumps(spec))


def test_a_spec_s_huge_number_is_named_in_words():
    """A review: a 5,000-digit number got Python's advice to call
    sys.set_int_max_str_digits, which no user of the command line can."""
    with pytest.raises(DesignError) as caught:
        sweep.parse_spec('{"grid": {"cam.base_radius_mm": [' + "9" * 5000 + "]}}")
    assert str(caught.value) == (
        "sweep spec: a JSON number of more than 4300 digits (no field takes one)"
    )


def test_a_chunk_is_bounded(tmp_path, capsys):
    """--chunk holds the batched core's memory (~2 MB a design): a value past
    MAX_CHUNK is refused before any work, not met when the machine runs out."""
    from camcore.cli import main

    (tmp_path / "s.json").write_text(json.dumps(SPEC))
    for n in (0, sweep.MAX_CHUNK + 1):
        args = ["sweep", str(tmp_path / "s.json"), "--out", str(tmp_path / "r.parquet")]
        assert main([*args, "--fast", "--chunk", str(n)]) == 2
        assert f"--chunk: from 1 to {sweep.MAX_CHUNK} designs" in capsys.readouterr().err
    assert not list(tmp_path.glob("r.parquet*"))


def test_the_progress_line_says_how_long_is_left():
    import io

    out = io.StringIO()
    sweep._progress(250, 1000, 5.0, out)  # 750 designs at 5 a second: 150 s
    assert "250/1000 designs, 5.0/s, ~2 min left" in out.getvalue()
    sweep._progress(1000, 1000, 5.0, out)
    assert out.getvalue().endswith("1000/1000 designs, 5.0/s   ")
    assert [sweep._duration(s) for s in (40, 720, 12600)] == ["40 s", "12 min", "3.5 h"]


def test_values_that_only_some_combinations_refuse_make_rows():
    """A value out of a field's own range, or one that fails only with the base's other
    fields, is a row that says why (another axis may make it a design); an infinite
    number is refused at once; integers beside floats, or too large for a 64-bit
    column, become floats."""
    spec = sweep.parse_spec(json.dumps({"grid": {"cam.base_radius_mm": [-5, 80, 1e23]}}))
    assert spec.axes[0][1] == (-5.0, 80.0, 1e23)
    for axis in ("[70, 1e400]", "[1" + "0" * 400 + "]", '{"from": 1, "to": 1e400, "num": 3}'):
        with pytest.raises(DesignError, match="finite"):
            sweep.parse_spec('{"grid": {"cam.base_radius_mm": ' + axis + "}}")
    assert sweep.parse_spec(json.dumps({"grid": {"cam.speed_rpm": [10**30]}})).axes[0][1] == (1e30,)


def test_cli_sweep_and_its_exit_codes(tmp_path):
    spec = tmp_path / "spec.json"
    spec.write_text(json.dumps({"grid": {"cam.base_radius_mm": [80, 85]}}))
    out = tmp_path / "r.parquet"
    run = subprocess.run(
        [sys.executable, "-m", "camcore.cli", "sweep", str(spec), "--out", str(out), "--no-verify"],
        capture_output=True,
        text=True,
    )
    assert run.returncode == 0, run.stderr
    assert "2/2 designs" in run.stderr and len(rows_of(out)) == 2
    valid = sum(r["valid"] for r in rows_of(out))
    assert f"(2 designs: {valid} valid, {2 - valid} break a limit, 0 not designs)" in run.stdout
    for args, message in [
        ([str(tmp_path / "none.json"), "--out", str(out)], "cannot read"),
        ([str(spec), "--out", str(tmp_path)], "is a directory"),
        ([str(spec), "--out", str(out), "--scheduler", "nonsense"], "--scheduler nonsense"),
        ([str(spec), "--out", str(out), "--scheduler", "x", "--workers", "2"], "give one"),
        ([str(spec), "--out", str(out), "--workers", "0"], "--workers 0: from 1 to"),
        ([str(spec), "--out", str(out), "--workers", "5000"], "--workers 5000: from 1 to"),
    ]:
        bad = subprocess.run(
            [sys.executable, "-m", "camcore.cli", "sweep", *args], capture_output=True, text=True
        )
        assert bad.returncode == 2 and message in bad.stderr, (args, bad.stderr)
        assert "Traceback" not in bad.stderr
    bad = subprocess.run(
        [sys.executable, "-m", "camcore.cli", "sweep", str(spec), "--out", str(spec)],
        capture_output=True,
        text=True,
    )
    assert bad.returncode == 2 and "that is the sweep's spec file" in bad.stderr


def test_dask_local_cluster_gives_the_same_rows(tmp_path):
    pytest.importorskip("dask.distributed")
    spec = sweep.parse_spec(json.dumps(SPEC))
    sweep.run(spec, tmp_path / "local.parquet", chunk=2, progress=None)
    sweep.run(spec, tmp_path / "dask.parquet", chunk=2, workers=2, progress=None)
    assert rows_of(tmp_path / "dask.parquet") == rows_of(tmp_path / "local.parquet")


def _run_on(cluster, spec, out, progress=None) -> None:
    """``spec`` swept on an existing Dask cluster (as --scheduler does), a chunk a design."""
    sweep.run(
        spec, out, chunk=1, verify=False, scheduler=cluster.scheduler_address, progress=progress
    )


def test_a_sweep_outlives_its_dask_workers_dying(tmp_path):
    """A review killed both workers of a cluster 0.2 s apart: the base design, scattered
    to the workers alone, was lost with them and the run ended as an internal error.
    Now each chunk carries its base, and Dask reruns the lost chunks on the workers
    their nannies restart: the rows are the in-process run's."""
    pytest.importorskip("dask.distributed")
    import os
    import signal
    import threading

    from dask.distributed import LocalCluster

    spec = sweep.parse_spec(
        json.dumps({"grid": {"cam.base_radius_mm": {"from": 70, "to": 90, "num": 12}}})
    )
    sweep.run(spec, tmp_path / "local.parquet", chunk=1, verify=False, progress=None)
    with LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=None) as cluster:
        pids = [nanny.pid for nanny in cluster.workers.values()]  # the worker processes
        done = threading.Event()

        def kill_after_first_chunk(done_designs, total, rate):
            if done_designs == 1:
                for pid in pids:
                    os.kill(pid, signal.SIGKILL)
                    time.sleep(0.2)
            done.set()

        _run_on(cluster, spec, tmp_path / "dask.parquet", kill_after_first_chunk)
        assert done.is_set() and {n.pid for n in cluster.workers.values()}.isdisjoint(pids)
    assert rows_of(tmp_path / "dask.parquet") == rows_of(tmp_path / "local.parquet")


def test_a_chunk_the_cluster_loses_for_good_says_the_run_resumes(tmp_path, monkeypatch, capsys):
    """Where Dask gives up on a chunk (its workers died running it again and again:
    KilledWorker), the run says what is kept and that the same command resumes (exit
    130, as for Ctrl-C), not an internal error."""
    pytest.importorskip("dask.distributed")
    from types import SimpleNamespace

    from dask.distributed import KilledWorker

    class Lost:
        def result(self):
            worker = SimpleNamespace(address="tcp://127.0.0.1:1")
            raise KilledWorker("checked_chunk-1234", worker, 3)

    with pytest.raises(sweep.ClusterLost, match=r"lost chunk 7 \(KilledWorker"):
        sweep.chunk_result(Lost(), 7)

    class Ok:
        def result(self):
            return [{"row": 1}]

    assert sweep.chunk_result(Ok(), 0) == [{"row": 1}]

    import contextlib

    from camcore import cli

    def lost(client, spec, chunk, todo, how, keep):
        keep(todo[0], sweep.run_chunk(spec.base, spec.chunk(todo[0], chunk), False))
        raise sweep.ClusterLost("the Dask cluster lost chunk 1 (KilledWorker: ...)")

    monkeypatch.setattr(sweep, "_cluster", lambda *where: contextlib.nullcontext(object()))
    monkeypatch.setattr(sweep, "_run_dask", lost)
    path = tmp_path / "spec.json"
    path.write_text(json.dumps(SPEC))
    argv = [str(path), "--out", str(tmp_path / "t.parquet"), "--chunk", "2", "--workers", "2"]
    assert cli.main(["sweep", *argv]) == 130
    said = capsys.readouterr().err
    assert "camcore: interrupted: the Dask cluster lost chunk 1 (KilledWorker" in said
    assert "2 of 6 designs are kept in" in said and "the same command resumes" in said
    assert "Traceback" not in said


def test_workers_running_another_camcore_are_refused():
    """An existing cluster (--scheduler) whose workers run another camcore would give
    another code's rows under this one's name: refused, naming them. A LocalCluster's
    workers share this process's install (the Dask tests above pass the check)."""
    from camcore import code_fingerprint

    class Cluster:
        def __init__(self, answer):
            self.answer = answer

        def run(self, fn):
            if isinstance(self.answer, Exception):
                raise self.answer
            return {w: fp or fn() for w, fp in self.answer.items()}

    sweep.same_code_on_workers(Cluster({"tcp://a:1": None, "tcp://b:2": None}))
    with pytest.raises(
        DesignError, match=r"1 of 2 Dask workers run another camcore \(tcp://b:2: code 0000"
    ):
        sweep.same_code_on_workers(Cluster({"tcp://a:1": None, "tcp://b:2": "0000"}))
    with pytest.raises(DesignError, match="cannot run this camcore .AttributeError"):
        sweep.same_code_on_workers(Cluster(AttributeError("no code_fingerprint")))
    assert len(code_fingerprint()) == 16
    # a worker that joins after that check: each chunk checks its worker's code
    with pytest.raises(DesignError, match="a Dask worker runs another camcore"):
        sweep.checked_chunk("0000", {}, [], False)
    spec = sweep.parse_spec(json.dumps(SPEC))
    points = spec.chunk(0, 2)
    assert sweep.checked_chunk(code_fingerprint(), spec.base, points, False) == sweep.run_chunk(
        spec.base, points, False
    )


def test_the_code_fingerprint_is_of_the_files_a_wheel_ships(tmp_path, monkeypatch):
    """A review: a stray file in the source tree (a Jupyter checkpoint's .py) changed
    the hash, so one commit made two codes. Only the package's modules and presets
    count, and each of them does."""
    import shutil

    import camcore

    root = Path(camcore.__file__).resolve().parent
    copy = tmp_path / "camcore"
    shutil.copytree(root, copy, ignore=shutil.ignore_patterns("__pycache__"))

    def fp(where: Path) -> str:
        monkeypatch.setattr(camcore, "__file__", str(where / "__init__.py"))
        camcore.code_fingerprint.cache_clear()
        try:
            return camcore.code_fingerprint()
        finally:
            camcore.code_fingerprint.cache_clear()

    same = fp(copy)
    (copy / ".ipynb_checkpoints").mkdir()
    (copy / ".ipynb_checkpoints" / "model-checkpoint.py").write_text("x = 1\n")
    (copy / "notes.json").write_text("{}")
    assert fp(copy) == same
    preset = copy / "presets" / "paper_example.json"
    preset.write_text(preset.read_text() + " ")
    assert fp(copy) != same


def test_sweeps_sharing_a_cluster_keep_their_own_base(tmp_path):
    """Two sweeps on one Dask cluster at once: the base design went out under its own
    keys ("cam", "name", ...), so the second sweep computed with the first one's."""
    pytest.importorskip("dask.distributed")
    from dask.distributed import Client, LocalCluster

    spec = sweep.parse_spec(
        json.dumps({"base": {"preset": "indexer_345"}, "grid": {"cam.width_mm": [10, 12]}})
    )
    sweep.run(spec, tmp_path / "local.parquet", chunk=1, verify=False, progress=None)
    with (
        LocalCluster(n_workers=1, processes=False, dashboard_address=None) as cluster,
        Client(cluster.scheduler_address) as other,
    ):
        paper = sweep.parse_spec(json.dumps(SPEC)).base
        held = other.scatter(paper, broadcast=True)  # as another sweep's base was  # noqa: F841
        _run_on(cluster, spec, tmp_path / "dask.parquet")
    assert rows_of(tmp_path / "dask.parquet") == rows_of(tmp_path / "local.parquet")


def test_the_fast_leaves_out_list_is_the_readme_s():
    from pathlib import Path

    from camcore import batch

    text = (Path(__file__).resolve().parents[1] / "README.md").read_text()
    fast = text[text.index("**`--fast`: the batched core**") :]
    fast = " ".join(fast[: fast.index("\n## ")].split())
    assert all(f"`{key}`" in fast for key in batch.LEFT_OUT)


def test_mixed_value_types_and_structured_values_join_into_one_table(tmp_path):
    """Chunks whose grid values differ in type (an int, then a float; a whole segment
    list) still make one table."""
    segs = [
        {"kind": "rise", "angle_deg": 180, "lift_mm": 10},
        {"kind": "fall", "angle_deg": 180, "lift_mm": 10},
    ]
    spec = sweep.parse_spec(
        json.dumps({"grid": {"cam.base_radius_mm": [80, 85.5], "motion.segments": [segs]}})
    )
    sweep.run(spec, tmp_path / "r.parquet", chunk=1, verify=False, progress=None)
    rows = rows_of(tmp_path / "r.parquet")
    assert [r["grid.cam.base_radius_mm"] for r in rows] == [80.0, 85.5]
    assert json.loads(rows[0]["grid.motion.segments"]) == segs


def _dominated_brute(v: np.ndarray) -> np.ndarray:
    """The definition, row by row: a finite row that another finite row is at least as
    good as in every column and better in one."""
    ok = np.isfinite(v).all(axis=1)
    out = ~ok
    for i in np.flatnonzero(ok):
        o = v[ok]
        out[i] = ((o <= v[i]).all(axis=1) & (o < v[i]).any(axis=1)).any()
    return out


@pytest.mark.parametrize("k", [1, 2, 3, 4])
def test_pareto_mask_against_a_brute_force_definition(k):
    """Every path of pareto_mask (one figure, the two-figure sweep, the blocks of three
    or more) against the definition: random, tied (few distinct values), anti-correlated
    (most points on the front) and NaN rows, across block boundaries."""
    from camcore.sweep import pareto_mask

    rng = np.random.default_rng(k)
    for trial in range(12):
        n = int(rng.integers(1, 1300))
        v = rng.integers(0, 5, (n, k)).astype(float) if trial % 2 else rng.random((n, k))
        if trial % 3 == 0:
            v[rng.integers(0, n, 4)] = np.nan
        if trial % 4 == 1 and k > 1:
            v[:, -1] = v[:, :-1].sum(axis=1) * -1.0  # a plane: anti-correlated
        mask = pareto_mask(v)
        np.testing.assert_array_equal(mask, ~_dominated_brute(v), err_msg=f"trial {trial}")
    assert pareto_mask(np.array([[1.0, 2.0], [2.0, 1.0], [2.0, 2.0]])).tolist() == [
        True,
        True,
        False,
    ]
    assert not pareto_mask(np.full((3, k), np.nan)).any()


def test_pareto_mask_takes_round_off_for_equal():
    """A review: a single roller (R 95.0 mm, 212.2 MPa) stayed on the front beside a
    single concave face (R 95.00000000000003 mm, 51.88 MPa), better only by round-off.
    Figures equal to 12 significant digits are equal; 13 digits apart still count."""
    from camcore.sweep import pareto_mask

    r = 95.00000000000003
    assert pareto_mask(np.array([[95.0, 212.2], [r, 51.88]])).tolist() == [False, True]
    for k in (2, 3):  # (both paths: the running minimum and the blocks)
        v = np.array([[95.0, 212.2, 1.0], [r, 51.88, 1.0]])[:, :k]
        assert pareto_mask(v).tolist() == [False, True]
    apart = 95.0 * (1 + 1e-11)  # a real difference, however small
    assert pareto_mask(np.array([[95.0, 212.2], [apart, 51.88]])).tolist() == [True, True]


def test_pareto_mask_of_a_large_front():
    """Thousands of points (the seeded filter of _front_by_blocks): all of a plane are
    on the front and a point behind it is not; random points with ties against the
    definition."""
    from camcore.sweep import pareto_mask

    rng = np.random.default_rng(5)
    v = rng.random((6000, 3))
    v[:, 2] = 2.0 - v[:, 0] - v[:, 1]
    v[-1] = v[0] + 0.01
    mask = pareto_mask(v)
    assert mask[:-1].all() and not mask[-1]
    # a large random sweep goes through the seeded filter first: the same front
    w = np.round(rng.random((5000, 3)), 2)
    np.testing.assert_array_equal(pareto_mask(w), ~_dominated_brute(w))


def test_first_violation_names_the_broken_limit():
    from camcore.sweep import first_violation

    assert first_violation({"valid": True, "error": None}) is None
    assert first_violation({"valid": False, "error": "cam.base_radius_mm: ..."}) == "not a design"
    row = {"valid": False, "error": None, "violations": '[{"code": "pressure_angle"}]'}
    assert first_violation(row) == "pressure_angle"


def test_fast_sweep_rows_equal_the_full_rows_where_both_report(tmp_path):
    """--fast (camcore.batch): the same grid columns, the same figures as the full rows,
    profile_checked = False; on a Dask LocalCluster the same rows; parts of a fast run
    are not mixed into a full one."""
    spec = sweep.parse_spec(json.dumps(SPEC))
    sweep.run(spec, tmp_path / "full.parquet", chunk=4, verify=False, progress=None)
    sweep.run(spec, tmp_path / "fast.parquet", chunk=4, fast=True, progress=None)
    full, fast = rows_of(tmp_path / "full.parquet"), rows_of(tmp_path / "fast.parquet")
    for f, r in zip(fast, full, strict=True):
        assert f["profile_checked"] is False and f["valid"] == r["valid"]
        shared = set(f) - {"profile_checked", "violations"}
        assert "contact_stress_max_MPa.cycle" in shared and "profile.vertices" not in shared
        for k in shared:
            a, b = f[k], r[k]
            if isinstance(a, float):
                assert a == pytest.approx(b, rel=1e-15), k
            elif isinstance(a, str) and a.startswith("["):
                assert json.loads(a) == pytest.approx(json.loads(b), rel=1e-15), k
            else:
                assert a == b, k
    pytest.importorskip("dask.distributed")
    sweep.run(spec, tmp_path / "dask.parquet", chunk=4, fast=True, workers=2, progress=None)
    assert rows_of(tmp_path / "dask.parquet") == fast

    def stop(done, total, t0):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        sweep.run(spec, tmp_path / "r.parquet", chunk=2, fast=True, progress=stop)
    with pytest.raises(DesignError, match="another sweep"):
        sweep.run(spec, tmp_path / "r.parquet", chunk=2, progress=None)


def test_a_fast_chunk_of_fine_designs_goes_through_the_core_in_parts(monkeypatch):
    """The batched core's memory goes with the grid samples, not the designs: a review
    measured 680 MB for 32 designs at 0.01 deg. A chunk passes through it in parts of at
    most BATCH_SAMPLES samples, and the rows are those of one pass."""
    from camcore import batch

    spec = sweep.parse_spec(
        json.dumps(
            {
                "grid": {
                    "cam.base_radius_mm": [70, 75, 80, 85, 90],
                    "limits.resolution_deg": [0.05],
                }
            }
        )
    )
    points = list(spec.points())
    whole = sweep.fast_rows(spec.base, points)
    seen = []
    real = batch.summaries
    monkeypatch.setattr(batch, "summaries", lambda ds: seen.append(len(ds)) or real(ds))
    monkeypatch.setattr(sweep, "BATCH_SAMPLES", 2 * 7201)  # two designs at 0.05 deg
    assert sweep.fast_rows(spec.base, points) == whole
    assert seen == [2, 2, 1]
    # a grid is counted as it is made: a short rise keeps its least samples however
    # fine the grid (a review: 48 rises of 7.5 deg at 0.1 deg hold 5,760, not 3,601)
    from camcore import motion
    from camcore.model import Design, load_preset

    data = load_preset("paper_example").model_dump(mode="json")
    data["motion"] = {
        "segments": [{"kind": "rise", "angle_deg": 7.5, "lift_mm": 0.1, "law": "cycloidal"}]
        + [{"kind": "fall", "angle_deg": 7.5, "lift_mm": 0.1, "law": "cycloidal"}]
        + [{"kind": "rise", "angle_deg": 7.5, "lift_mm": 0.1, "law": "cycloidal"}] * 23
        + [{"kind": "fall", "angle_deg": 7.5, "lift_mm": 0.1, "law": "cycloidal"}] * 23
    }
    short = Design.model_validate(data)
    n = motion.theta_grid(short).size
    assert n >= 48 * motion.MIN_MOTION_STEPS > 3601
    monkeypatch.setattr(sweep, "BATCH_SAMPLES", 2 * n)
    assert [len(p) for p in sweep._parts_of([short] * 5)] == [2, 2, 1]


def test_cli_fast_sweep(tmp_path):
    spec = tmp_path / "spec.json"
    spec.write_text(json.dumps({"grid": {"cam.base_radius_mm": {"from": 60, "to": 90, "num": 7}}}))
    out = tmp_path / "r.parquet"
    run = subprocess.run(
        [sys.executable, "-m", "camcore.cli", "sweep", str(spec), "--out", str(out), "--fast"],
        capture_output=True,
        text=True,
    )
    assert run.returncode == 0, run.stderr
    rows = rows_of(out)
    assert len(rows) == 7 and not any(r["profile_checked"] for r in rows)
    assert [r["grid.cam.base_radius_mm"] for r in rows] == [60, 65, 70, 75, 80, 85, 90]


def _paper_rows(grid: dict) -> list[dict]:
    """The batched rows of a sweep of ``grid`` around the paper's example."""
    spec = sweep.parse_spec(json.dumps({"base": {"preset": "paper_example"}, "grid": grid}))
    return sweep.run_chunk(spec.base, list(spec.points()), fast=True)


def test_explore_counts_a_design_swept_over_a_field_it_ignores_once():
    """Sweeping the double follower's offset e over a single follower repeats one design:
    ``distinct`` keeps the first of them, the Pareto front lists it once, and the map
    says which field a follower does not use."""
    from camcore.explore import distinct, explore_png, ignored_fields, pareto

    rows = _paper_rows(
        {
            "follower.kind": ["single_concave", "double_concave"],
            "cam.base_radius_mm": [80, 90],
            "follower.offset_mm": [20, 30],
        }
    )
    first = distinct(rows)
    assert len(rows) == 8 and int(first.sum()) == 6  # 2 single (e ignored) + 4 double
    signed = [
        dict(r, **{"grid.follower.single_offset_mm": z}) for r in rows[:1] for z in (0.0, -0.0)
    ]
    assert distinct(signed).tolist() == [True, False]  # -0.0 and 0.0 are one design
    singles = [r for r in rows if r["grid.follower.kind"] == "single_concave"]
    assert all(ignored_fields(r) == ["follower.offset_mm"] for r in singles)
    names = ["cam_size", "stress"]
    front = pareto(rows, names)
    keys = [(rows[i]["grid.follower.kind"], rows[i]["grid.cam.base_radius_mm"]) for i in front]
    single = [k for k in keys if k[0] == "single_concave"]
    assert single and len(single) == len(set(single))  # each single design once
    png = explore_png(
        rows, ("cam.base_radius_mm", "r_b"), ("follower.offset_mm", "e"), names, front
    )
    assert png.startswith(b"\x89PNG")


def test_every_follower_s_map_spans_the_whole_sweep():
    """A sweep cancelled during the last follower: its map had shrunk to the 60-63.6 mm
    it reached, as if that were the whole range. All maps share the sweep's axes."""
    from camcore.explore import explore_figure, pareto

    rows = _paper_rows(
        {
            "follower.kind": ["single_roller", "double_concave"],
            "cam.base_radius_mm": [60, 85, 110],
            "follower.offset_mm": [20, 30],
        }
    )
    rows = rows[:7]  # cancelled: the double concave faces reached 60 mm, e = 20 only
    names = ["cam_size", "stress"]
    fig = explore_figure(
        rows,
        ("cam.base_radius_mm", "r_b"),
        ("follower.offset_mm", "e"),
        names,
        pareto(rows, names),
    )
    maps = fig.axes[:2]
    assert [ax.get_title() for ax in maps] == [
        "single roller\n(does not use y)",  # (the single roller has no offset e)
        "double concave",
    ]
    (x0, x1), (y0, y1) = maps[0].get_xlim(), maps[0].get_ylim()
    assert x0 < 60 and x1 > 110 and y0 < 20 and y1 > 30
    assert maps[1].get_xlim() == (x0, x1) and maps[1].get_ylim() == (y0, y1)
    # cancelled during the first follower: the sweep's own ranges, not the rows'
    first = rows[:1]
    fig = explore_figure(
        first,
        ("cam.base_radius_mm", "r_b"),
        ("follower.offset_mm", "e"),
        names,
        pareto(first, names),
        limits=((60, 110), (20, 30)),
    )
    assert fig.axes[0].get_xlim() == (x0, x1) and fig.axes[0].get_ylim() == (y0, y1)


def test_the_map_is_drawn_for_the_panel_it_is_shown_in():
    """A review read the map's text at ~5 px: it was drawn 760 px wide and shown in the
    app's 384 px panel. Now every text of it is at least 10 px as shown, in the narrow
    panel as in the 1000 px wide one, the PNG has twice the shown pixels, and the
    followers' maps stand side by side as many as fit (2 narrow, 4 wide)."""
    from matplotlib.text import Text

    from app.layout import NARROW_PANEL_PX
    from camcore.explore import DPI, PANEL_PX, PT_PX, explore_figure, explore_png, pareto

    assert PANEL_PX == NARROW_PANEL_PX
    rows = _paper_rows(
        {
            "follower.kind": ["single_roller", "double_roller", "single_concave", "double_concave"],
            "cam.base_radius_mm": [60, 85, 110],
            "follower.offset_mm": [20, 30],
        }
    )
    names = ["cam_size", "stress"]
    front = pareto(rows, names)
    axes = (("cam.base_radius_mm", "r_b [mm]"), ("follower.offset_mm", "e [mm]"))
    for shown, side_by_side in ((PANEL_PX, 2), (1000, 4)):
        fig = explore_figure(rows, *axes, names, front, shown)
        assert fig.get_figwidth() * DPI == pytest.approx(2 * shown)
        texts = [t for t in fig.findobj(Text) if t.get_text().strip() and t.get_visible()]
        assert len(texts) > 20
        assert min(t.get_fontsize() for t in texts) * PT_PX >= 10.0  # [px] as shown
        fig.canvas.draw()
        tops = [round(ax.get_position().y1, 3) for ax in fig.axes[:4]]
        assert tops.count(tops[0]) == side_by_side
        png = explore_png(rows, *axes, names, front, shown)
        assert int.from_bytes(png[16:20], "big") == 2 * shown  # the PNG's width


def test_one_follower_s_map_stands_beside_its_front_in_a_wide_panel():
    """One follower in the 1000 px panel: its map had the panel's width and as much
    height, and the front came below it, 1,280 px down (a review at 1920 px). Now the
    map and the front stand side by side and the figure is wider than tall; the narrow
    panel keeps them one above the other."""
    from camcore.explore import PANEL_PX, explore_figure, pareto

    rows = _paper_rows({"cam.base_radius_mm": [60, 85, 110], "follower.offset_mm": [20, 30]})
    names = ["cam_size", "stress"]
    axes = (("cam.base_radius_mm", "r_b [mm]"), ("follower.offset_mm", "e [mm]"))
    wide = explore_figure(rows, *axes, names, pareto(rows, names), 1000)
    wide.canvas.draw()
    the_map, the_front = (ax.get_position() for ax in wide.axes[:2])
    assert the_map.x1 < the_front.x0 and abs(the_map.y1 - the_front.y1) < 0.05
    assert wide.get_figheight() < 0.6 * wide.get_figwidth()
    narrow = explore_figure(rows, *axes, names, pareto(rows, names), PANEL_PX)
    narrow.canvas.draw()
    assert narrow.axes[0].get_position().y0 > narrow.axes[1].get_position().y1


def test_a_third_figure_colours_the_designs_and_widens_the_front():
    """Three figures (issue 12's cam size vs. stress vs. pressure angle): the front of
    all three holds the front of the first two and the design least in the third; the
    panel colours the valid designs by the third (a colour bar says which) and rings
    the front instead of joining it (in the plane of two figures it is no curve)."""
    from camcore.explore import explore_figure, figure_values, pareto

    rows = _paper_rows(
        {
            "follower.kind": ["double_roller", "double_concave"],
            "cam.base_radius_mm": [45, 60, 80, 110],
            "follower.offset_mm": [10, 25],
        }
    )
    two, three = ["cam_size", "stress"], ["cam_size", "stress", "pressure_angle"]
    f2, f3 = pareto(rows, two), pareto(rows, three)
    assert set(f2) < set(f3)
    v = figure_values(rows, three)
    valid = np.array([bool(r["valid"]) for r in rows])
    assert int(np.flatnonzero(valid)[np.argmin(v[valid, 2])]) in set(f3)
    fig = explore_figure(
        rows, ("cam.base_radius_mm", "r_b"), ("follower.offset_mm", "e"), three, f3
    )
    panel, bar = fig.axes[-2], fig.axes[-1]
    assert bar.get_ylabel() == "max pressure angle [°]"
    lo, hi = bar.get_ylim()
    assert lo == pytest.approx(np.nanmin(v[valid, 2])) and hi == pytest.approx(
        np.nanmax(v[valid, 2])
    )
    assert "all three figures" in panel.get_title() and not panel.get_lines()
    flat = explore_figure(rows, ("cam.base_radius_mm", "r_b"), ("follower.offset_mm", "e"), two, f2)
    assert len(flat.axes) == len(fig.axes) - 1 and flat.axes[-1].get_lines()  # the line


def test_a_refused_copy_does_not_hide_a_valid_design():
    """A field a follower ignores is still checked against its own limits: a concave
    face swept over roller radius 0 (refused) and 10 is one design, and the valid row
    stands for it (the refused one came first and hid the concave faces)."""
    from camcore.explore import distinct, pareto

    rows = _paper_rows(
        {"follower.kind": ["single_roller", "double_concave"], "follower.roller_radius_mm": [0, 10]}
    )
    first = distinct(rows)
    concave = [i for i, r in enumerate(rows) if r["grid.follower.kind"] == "double_concave"]
    assert [rows[i].get("error") is None for i in concave] == [False, True]
    assert first[concave].tolist() == [False, True]
    assert concave[1] in pareto(rows, ["cam_size", "stress"])


@pytest.mark.parametrize("fast", [False, True])
def test_points_that_make_one_design_are_analysed_once(monkeypatch, fast):
    """The four followers over roller radius x face radius (the paper's claim as a
    design space): a roller ignores the face radius and a face the roller radius, so
    18 points make 6 designs (and 6 refusals, face radius 0). Each design is analysed
    once, and every row still equals the row of its point computed alone (its own
    grid values, the shared figures)."""
    spec = sweep.parse_spec(
        json.dumps(
            {
                "grid": {
                    "follower.kind": ["single_roller", "double_concave", "single_concave"],
                    "follower.roller_radius_mm": [8, 12],
                    "follower.face_radius_mm": [-250, -300, 0],  # 0: refused, a row that says why
                }
            }
        )
    )
    points = list(spec.points())
    same = sweep.same_designs(spec.base, points)
    assert len(set(same)) == 3 * 2 + 6  # each follower twice; each refused point alone
    analysed: list = []
    if fast:
        from camcore import batch

        real = batch.summaries
        monkeypatch.setattr(batch, "summaries", lambda ds: analysed.extend(ds) or real(ds))
    else:
        from camcore import analysis

        real_an = analysis.analyze
        monkeypatch.setattr(
            analysis, "analyze", lambda d, **k: analysed.append(d) or real_an(d, **k)
        )
    rows = sweep.run_chunk(spec.base, points, verify=False, fast=fast)
    monkeypatch.undo()
    assert len(analysed) == 6
    alone = (
        sweep.fast_rows(spec.base, [p]) if fast else [sweep.row(spec.base, p, False)]
        for p in points
    )
    assert rows == [r for (r,) in alone]
    assert sum(r["error"] is not None for r in rows) == 6  # face radius 0, for every follower


def test_a_design_repeated_in_a_later_chunk_is_not_analysed_again(tmp_path, monkeypatch):
    """A concave face swept over roller radius (which it ignores) x base radius, two
    points per chunk: the repeats fall in later chunks, and the run in this process
    reuses the rows it has (3 chunks, 2 designs analysed); every row still equals the
    row of its own point."""
    from camcore import analysis

    grid = {
        "follower.kind": ["double_concave"],
        "follower.roller_radius_mm": [8, 10, 12],
        "cam.base_radius_mm": [75, 80],
    }
    spec = sweep.parse_spec(json.dumps({"grid": grid}))
    analysed: list = []
    real = analysis.analyze
    monkeypatch.setattr(analysis, "analyze", lambda d, **k: analysed.append(d) or real(d, **k))
    n = sweep.run(spec, tmp_path / "r.parquet", chunk=2, verify=False, progress=None)
    monkeypatch.undo()
    assert n == 6 and len(analysed) == 2
    rows = rows_of(tmp_path / "r.parquet")
    alone = [sweep.row(spec.base, p, verify=False) for p in spec.points()]
    assert [r["grid.follower.roller_radius_mm"] for r in rows] == [8, 8, 10, 10, 12, 12]
    for r, a in zip(rows, alone, strict=True):
        assert {k: r[k] for k in a} == a


PARETO_SPEC = {
    "base": {"preset": "paper_example"},
    "grid": {
        "cam.base_radius_mm": [12, 25, 45, 70, 100],
        "cam.bore_diameter_mm": [0, 40],
        "follower.roller_radius_mm": [10, 30],
        "follower.kind": ["single_roller", "double_concave"],
    },
}


@pytest.fixture(scope="module")
def pareto_table(tmp_path_factory):
    """A full sweep with valid designs, broken limits and points that are no design."""
    out = tmp_path_factory.mktemp("pareto") / "r.parquet"
    spec = sweep.parse_spec(json.dumps(PARETO_SPEC))
    sweep.run(spec, out, chunk=8, verify=False, progress=None)
    return out


def test_table_front_is_the_front_of_the_rows(pareto_table):
    """camcore pareto's column-wise front equals the definition applied to the rows as
    dicts: valid rows only, each design once (a concave face swept over roller radii is
    one design, its roller radius shown as None), ordered by the first figure; the
    counts and first broken limits equal those of the rows."""
    from collections import Counter

    from camcore.explore import FIGURES, ignored_fields, table_front

    rows = rows_of(pareto_table)
    names = ["cam_size", "stress", "pressure_angle"]
    f = table_front(pareto_table, names)
    valid = [r for r in rows if r["valid"] and r["error"] is None]
    assert 0 < len(valid) < len(rows)
    assert (f.rows, f.valid) == (len(rows), len(valid))
    assert f.refused == sum(r["error"] is not None for r in rows) > 0
    broken = [sweep.first_violation(r) for r in rows if not r["valid"] and r["error"] is None]
    assert f.first_limits == dict(Counter(broken)) and f.first_limits
    assert f.profile_checked

    v = np.array([[FIGURES[n].get(r) for n in names] for r in valid], dtype=float)
    on = ~_dominated_brute(v)
    want = set()
    for r, keep in zip(valid, on, strict=True):
        if keep:
            drop = ignored_fields(r)
            want.add(
                tuple(
                    (k[5:], None if k[5:] in drop else r[k])
                    for k in sorted(r)
                    if k.startswith("grid.")
                )
            )
    got = [tuple(sorted(d["grid"].items())) for d in f.front]
    assert len(got) == len(set(got)) and set(got) == want
    assert f.repeats == int(on.sum()) - len(want) > 0
    firsts = [d["figures"]["cam_size"] for d in f.front]
    assert firsts == sorted(firsts)
    concave = [d for d in f.front if d["grid"]["follower.kind"] == "double_concave"]
    assert concave and all(d["grid"]["follower.roller_radius_mm"] is None for d in concave)


def test_cli_pareto_and_its_exit_codes(pareto_table, tmp_path):
    """The front as a table and as JSON; bad figure names, a file that is not a sweep
    table and a figure the table lacks are refused (exit 2); a table with no valid
    design exits 1."""
    from camcore.explore import table_front

    def run(*args):
        return subprocess.run(
            [sys.executable, "-m", "camcore.cli", "pareto", *map(str, args)],
            capture_output=True,
            text=True,
        )

    names = ["cam_size", "stress"]
    front = table_front(pareto_table, names).front
    text = run(pareto_table, "--figures", ",".join(names), "--top", 2)
    assert text.returncode == 0, text.stderr
    lines = text.stdout.splitlines()
    assert f"smaller is better: {len(front)} designs" in text.stdout
    assert "first limit broken: " in text.stdout
    assert lines[-1] == f"(2 of {len(front)} shown; --top N or --json for more)"
    first = lines[-3].split()  # the first design's row: number, grid values, figures
    assert first[0] == "1" and first[-2:] == [f"{front[0]['figures'][n]:.4g}" for n in names]
    js = run(pareto_table, "--figures", ",".join(names), "--json")
    assert js.returncode == 0 and json.loads(js.stdout)["front"] == front

    for args, message in [
        ((pareto_table, "--figures", "size"), "--figures 'size'"),
        ((pareto_table, "--figures", "stress,stress"), "distinct"),
        ((pareto_table, "--top", 0), "--top"),
        ((tmp_path / "none.parquet",), "No such file or directory"),
        ((pareto_table.parent,), "not a regular file"),
    ]:
        bad = run(*args)
        assert bad.returncode == 2 and message in bad.stderr, (args, bad.stderr)
        assert "Traceback" not in bad.stderr
    spec = tmp_path / "spec.json"
    for radii, valid in (([12, 14, 80], True), ([12, 14], False)):
        spec.write_text(json.dumps({"grid": {"cam.base_radius_mm": radii}}))
        fast = tmp_path / f"fast{len(radii)}.parquet"
        sweep.run(sweep.load_spec(spec), fast, verify=False, fast=True, progress=None)
        wear = run(fast, "--figures", "cam_size,wear")
        if valid:  # valid rows and no wear column: the figure is refused
            assert wear.returncode == 2 and "a --fast sweep leaves it out" in wear.stderr
        else:  # no valid row: nothing to rank, whatever the figures
            assert wear.returncode == 1 and "no valid design" in wear.stdout
            assert "0 valid, 2 break a limit" in wear.stdout


def test_a_front_design_comes_out_as_a_design_file(pareto_table, tmp_path):
    """The table keeps its SPEC, so `camcore pareto --design N` prints the very design
    of the front's row N: its report gives the figures the front lists, its fields the
    row's grid values; a table without its SPEC is refused, and so is an N off the
    front."""
    import pyarrow.parquet as pq

    from camcore.analysis import analyze
    from camcore.explore import FIGURES, table_front
    from camcore.model import design_from_json
    from camcore.report import summary
    from camcore.sweep import flatten

    spec = sweep.parse_spec(json.dumps(PARETO_SPEC))
    assert sweep.parse_spec(spec.document()) == spec
    names = ["cam_size", "stress", "pressure_angle"]
    front = table_front(pareto_table, names).front
    rows = rows_of(pareto_table)
    for n in (1, len(front)):
        run = subprocess.run(
            [sys.executable, "-m", "camcore.cli", "pareto", str(pareto_table), "--design", str(n)],
            capture_output=True,
            text=True,
        )
        assert run.returncode == 0, run.stderr
        design = design_from_json(run.stdout)
        entry = front[n - 1]
        flat = flatten(summary(analyze(design, verify=False)))
        assert {m: FIGURES[m].get(flat) for m in names} == entry["figures"]
        row = rows[entry["row"]]
        assert design.cam.base_radius_mm == row["grid.cam.base_radius_mm"]
        assert design.follower.kind.value == row["grid.follower.kind"]
        assert design.follower.roller_radius_mm == row["grid.follower.roller_radius_mm"]
    bad = subprocess.run(
        [sys.executable, "-m", "camcore.cli", "pareto", str(pareto_table), "--design", "0"],
        capture_output=True,
        text=True,
    )
    assert bad.returncode == 2 and f"designs 1 to {len(front)}" in bad.stderr
    bare = tmp_path / "bare.parquet"
    pq.write_table(pq.read_table(pareto_table).replace_schema_metadata(None), bare)
    with pytest.raises(FileError, match="does not keep its sweep spec"):
        sweep.design_of_row(bare, 0)


def test_pareto_of_odd_tables(pareto_table, tmp_path):
    """A sweep whose every point is no design (its table has no figure columns) has no
    front (exit 1, not a refusal); valid rows without a chosen figure are counted and
    said to be left out; a table with the right column names holding something else
    is refused in one line, never a traceback."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    from camcore.explore import table_front

    def cli(path, *args):
        return subprocess.run(
            [sys.executable, "-m", "camcore.cli", "pareto", str(path), *args],
            capture_output=True,
            text=True,
        )

    spec = tmp_path / "spec.json"
    spec.write_text(json.dumps({"grid": {"cam.bore_diameter_mm": [200, 300]}}))
    none = tmp_path / "none.parquet"
    sweep.run(sweep.load_spec(spec), none, verify=False, progress=None)
    run = cli(none)
    assert run.returncode == 1 and "2 rows: 0 valid, 0 break a limit, 2 not designs" in run.stdout

    t = pq.read_table(pareto_table)
    col = "contact_stress_max_MPa.cycle"
    valid = t.column("valid").to_numpy(zero_copy_only=False)
    lacking = np.flatnonzero(valid)[:3]
    stress = t.column(col).to_pylist()
    for i in lacking:
        stress[i] = None
    holes = tmp_path / "holes.parquet"
    pq.write_table(t.set_column(t.schema.get_field_index(col), col, pa.array(stress)), holes)
    f = table_front(holes, ["cam_size", "stress"])
    assert f.lacking == 3 and f.lacking_by == {"stress": 3} and f.valid == int(valid.sum())
    assert all(d["row"] not in lacking for d in f.front)
    run = cli(holes, "--figures", "cam_size,stress")
    # (rollers' holes: not put down to knife edges, as before a CLI review)
    assert "3 valid rows left out: stress missing in 3\n" in run.stdout

    def swapped(name, values):
        out = tmp_path / f"{name}.parquet"
        i = t.schema.get_field_index(name)
        pq.write_table(t.set_column(i, name, pa.array(values)), out)
        return out

    n = t.num_rows
    for path in (
        swapped("violations", ["not json"] * n),
        swapped("violations", ['["x"]'] * n),
        swapped("violations", [[1, 2]] * n),
        swapped("dwell_radius_mm", ["x"] * n),
        pq.write_table(t.select(["valid", "error"]), tmp_path / "nogrid.parquet")
        or tmp_path / "nogrid.parquet",
    ):
        bad = cli(path)
        assert bad.returncode == 2 and "not a camcore sweep table" in bad.stderr, bad.stderr
        assert "Traceback" not in bad.stderr


def test_pareto_prints_a_table_s_text_printable_and_reads_a_bounded_spec(pareto_table, tmp_path):
    """A security review: a column name with terminal escapes (a table is a file from
    anywhere) reached the terminal raw in camcore pareto's table, and a 2 MB spec kept in
    a table's metadata was read although a spec file is capped at MAX_SPEC_BYTES."""
    import pyarrow.parquet as pq

    t = pq.read_table(pareto_table)
    grid = [n for n in t.column_names if n.startswith("grid.")]
    evil = "grid.\x1b]0;PWNED\x07\x1b[2Jcam"
    names = [evil if n == grid[0] else n for n in t.column_names]
    path = tmp_path / "evil.parquet"
    pq.write_table(t.rename_columns(names), path)
    run = subprocess.run(
        [sys.executable, "-m", "camcore.cli", "pareto", str(path)], capture_output=True, text=True
    )
    assert run.returncode in (0, 1) and "\\u001b]0;PWNED" in run.stdout
    assert "\x1b" not in run.stdout + run.stderr
    meta = dict(t.schema.metadata)
    meta[sweep.SPEC_METADATA.encode()] = b" " * (sweep.MAX_SPEC_BYTES + 1)
    big = tmp_path / "big.parquet"
    pq.write_table(t.replace_schema_metadata(meta), big)
    with pytest.raises(FileError, match="its sweep spec is 1000001 bytes"):
        sweep.design_of_row(big, 0)


def test_a_grid_of_more_fields_than_a_design_has_is_refused_at_once():
    """A security review: 12,000 grid keys were compared pairwise for 35 s before the
    first unknown field was named."""
    grid = {f"cam.x{i}": [1] for i in range(sweep.MAX_AXES + 1)}
    with pytest.raises(DesignError, match=f"grid: {sweep.MAX_AXES + 1} fields; at most"):
        sweep.parse_spec(json.dumps({"grid": grid}))


def test_a_point_that_changes_the_follower_renames_it():
    """A review: Explore's 'Load this design' brought '... (double concave faces)' with a
    single roller; a grid point of another kind renames the follower the name says."""
    from camcore.model import load_preset

    base = load_preset("paper_example").model_dump(mode="json")
    roller = sweep.design_at(base, {"follower.kind": "single_roller"})
    assert roller.name == "Chuang, Hsu & Chang, Section 6 example (single roller)"
    same = sweep.design_at(base, {"cam.base_radius_mm": 90})
    assert same.name == base["name"]


def test_the_offered_front_designs_spread_along_the_front():
    """A front longer than the list offers designs spread along it, both ends kept, in
    order (a review: the first 30 of a 107-design front were all small cams, and the
    low-stress large ones could not be loaded), evenly in the figures' plane: where
    the front crowds (designs 0.01 mm apart) it offers one of the crowd, not many (a
    second review)."""
    from camcore.explore import offered

    front = np.arange(100, 207)  # 107 row indices, ordered by the first figure
    values = np.zeros((207, 2))
    values[front, 0] = np.linspace(0.0, 1.0, 107)
    values[front, 1] = 1.0 - values[front, 0]
    picks = offered(front, values, 30)
    assert len(picks) == 30 and picks[0] == 100 and picks[-1] == 206
    assert np.all(np.diff(picks) > 0) and np.all(np.diff(picks) <= 5)  # no big gap
    assert np.array_equal(offered(front[:12], values, 30), front[:12])  # short: all of it
    # 80 designs crowded within 1e-4 at one end, 27 spread over the rest
    values[front, 0] = np.concatenate([np.linspace(0, 1e-4, 80), np.linspace(0.04, 1.0, 27)])
    values[front, 1] = 1.0 - values[front, 0]
    picks = offered(front, values, 30)
    crowd = picks[picks < 180]
    assert len(crowd) == 1 and set(front[80:]) <= set(picks)  # every spread design
    gaps = np.diff(values[picks, 0])
    assert gaps.max() < 0.06  # no stretch of the front left without an offer


def test_each_limit_keeps_its_colour_from_sweep_to_sweep():
    """The map's colour of a limit is its own, whichever others a sweep meets (a
    review: red meant one limit in one run and another in the next); every code the
    checks report has one, all distinct."""
    import re
    from pathlib import Path

    from camcore import checks
    from camcore.explore import OUTCOMES, _colour, explore_figure

    source = Path(checks.__file__).read_text()
    assert set(re.findall(r'Violation\(\s*"(\w+)"', source)) == set(checks.CODES)
    assert len({_colour(c) for c in OUTCOMES}) == len(OUTCOMES)

    def row(r_b: float, codes: list[str]) -> dict:
        violations = json.dumps([{"code": c} for c in codes])
        return {
            "grid.follower.kind": "single_roller",
            "grid.cam.base_radius_mm": r_b,
            "grid.cam.width_mm": 10.0,
            **{"valid": not codes, "error": None, "violations": violations},
        }

    def colour_of_first_cell(rows):
        fig = explore_figure(
            rows,
            ("cam.base_radius_mm", "r_b"),
            ("cam.width_mm", "w"),
            ["cam_size", "stress"],
            np.array([], int),
        )
        return tuple(fig.axes[0].collections[0].get_facecolors()[0])

    # a sweep of no valid design says so where the front would be
    fig = explore_figure(
        [row(60, ["pressure_angle"])],
        ("cam.base_radius_mm", "r_b"),
        ("cam.width_mm", "w"),
        ["cam_size", "stress"],
        np.array([], int),
    )
    assert "no valid design in this sweep" in [t.get_text() for t in fig.axes[-1].texts]
    one = colour_of_first_cell([row(60, ["pressure_angle"]), row(70, [])])
    two = colour_of_first_cell([row(60, ["pressure_angle"]), row(70, ["curvature_convex"])])
    assert one == two


def test_a_grid_too_large_is_refused_before_its_values_are_made(monkeypatch):
    """A review: 30 ranges of 100,000 values each built 3 million floats (118 MB, 2.9 s)
    before the grid's size was refused. The size is counted from the spec as written
    (a 4,000-digit num too), and no axis is built."""
    import tracemalloc

    built = []
    monkeypatch.setattr(sweep, "axis_values", lambda *a: built.append(a) or ())
    fields = [f"motion.segments.{i}.angle_deg" for i in range(4)]
    fields += [f"motion.segments.{i}.lift_mm" for i in range(4)]
    grid = {f: {"from": 1, "to": 2, "num": 100_000} for f in fields}
    tracemalloc.start()
    with pytest.raises(DesignError, match="grid: over 10\\^15 designs; at most"):
        sweep.parse_spec(json.dumps({"grid": grid}))
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert not built and peak < 5_000_000
    huge = '{"grid": {"cam.width_mm": {"from": 1, "to": 2, "num": 1%s}}}' % ("0" * 4000)
    with pytest.raises(DesignError, match="over 10\\^15 designs"):
        sweep.parse_spec(huge)


def test_a_spec_can_name_its_base_design_file(tmp_path, capsys):
    """A designer's review pasted a whole design into the spec: a base {"file": NAME} is
    read beside the spec file, strictly (a bad file says why); the spec's document
    keeps the design itself; a spec not read from a file (the app's) names no file."""
    from camcore.model import design_to_json, load_preset

    d = load_preset("paper_example").with_kind("single_roller")
    (tmp_path / "mine.json").write_text(design_to_json(d))
    spec_path = tmp_path / "spec.json"
    spec_path.write_text(
        json.dumps({"base": {"file": "mine.json"}, "grid": {"cam.width_mm": [10, 12]}})
    )
    spec = sweep.load_spec(spec_path)
    assert spec.base == json.loads(d.model_dump_json()) and spec.size == 2
    assert json.loads(spec.document())["base"]["follower"]["kind"] == "single_roller"
    with pytest.raises(DesignError, match="beside the spec file"):
        sweep.parse_spec(spec_path.read_text())
    (tmp_path / "mine.json").write_text('{"cam": {"base_radius_mm": -5}}')
    with pytest.raises(DesignError, match="base_radius_mm"):
        sweep.load_spec(spec_path)
    # a file leaving inputs out: those no axis gives are said, as report says them
    data = json.loads(design_to_json(d))
    del data["cam"]["base_radius_mm"], data["cam"]["width_mm"], data["dynamics"]
    (tmp_path / "mine.json").write_text(json.dumps(data))
    grid = {"cam.width_mm": [10, 12]}
    spec_path.write_text(json.dumps({"base": {"file": "mine.json"}, "grid": grid}))
    spec = sweep.load_spec(spec_path)
    assert "cam.base_radius_mm = 80.0" in spec.defaulted
    assert "dynamics (the whole group)" in spec.defaulted
    assert not any("width_mm" in x for x in spec.defaulted)  # the grid gives it
    assert not any("face_radius_mm" in x for x in spec.defaulted)  # a roller's file
    kinds = {"cam.width_mm": [10], "follower.kind": ["single_roller", "double_concave"]}
    spec_path.write_text(json.dumps({"base": {"file": "mine.json"}, "grid": kinds}))
    data["follower"].pop("face_radius_mm")
    (tmp_path / "mine.json").write_text(json.dumps(data))
    assert "follower.face_radius_mm = -250.0" in sweep.load_spec(spec_path).defaulted
    (tmp_path / "mine.json").write_text(json.dumps(data | {"dynamics": {}}))
    whole = {"dynamics": [json.loads(d.dynamics.model_dump_json())], "cam.width_mm": [10]}
    spec_path.write_text(json.dumps({"base": {"file": "mine.json"}, "grid": whole}))
    assert not any("dynamics" in x for x in sweep.load_spec(spec_path).defaulted)
    spec_path.write_text(json.dumps({"base": {"file": "mine.json"}, "grid": grid}))
    from camcore.cli import main

    assert main(["sweep", str(spec_path), "--out", str(tmp_path / "r.parquet"), "--fast"]) == 0
    assert (
        "spec.json: not in its base design file mine.json, so at their defaults: "
        "cam.base_radius_mm = 80.0" in (capsys.readouterr().err)
    )
    # the table is never written over the base design (a review: it was, exit 0)
    kept = (tmp_path / "mine.json").read_bytes()
    for out in ("mine.json", "sub/../mine.json"):
        (tmp_path / "sub").mkdir(exist_ok=True)
        assert main(["sweep", str(spec_path), "--out", str(tmp_path / out), "--fast"]) == 2
        assert "that is the spec's base design file" in capsys.readouterr().err
    assert (tmp_path / "mine.json").read_bytes() == kept
    (tmp_path / "sub").rmdir()
    # a grid of other kinds: the base's own kind's fields are not said (none runs it)
    other = {"cam.width_mm": [10], "follower.kind": ["double_concave"]}
    spec_path.write_text(json.dumps({"base": {"file": "mine.json"}, "grid": other}))
    shown = sweep.load_spec(spec_path).defaulted
    assert "follower.face_radius_mm = -250.0" in shown
    assert not any("roller_radius" in x or "single_offset" in x for x in shown)
    spec_path.write_text(
        json.dumps({"base": {"file": "absent.json"}, "grid": {"cam.width_mm": [10]}})
    )
    with pytest.raises(DesignError, match="absent.json"):
        sweep.load_spec(spec_path)
    # only the spec's folder or below (a review: a shared spec read ~/secret.json and
    # quoted its keys); a subfolder is fine
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "spec.json").write_text("{}")
    (tmp_path / "sub" / "deeper").mkdir()
    (tmp_path / "sub" / "deeper" / "mine.json").write_text(design_to_json(d))
    for name in ("../mine.json", str(tmp_path / "mine.json"), "deeper/../../mine.json"):
        (tmp_path / "sub" / "spec.json").write_text(
            json.dumps({"base": {"file": name}, "grid": grid})
        )
        with pytest.raises(DesignError, match="in the spec file's folder or below it"):
            sweep.load_spec(tmp_path / "sub" / "spec.json")
    (tmp_path / "sub" / "spec.json").write_text(
        json.dumps({"base": {"file": "deeper/mine.json"}, "grid": grid})
    )
    assert sweep.load_spec(tmp_path / "sub" / "spec.json").size == 2
    # a NUL in the name is bad input, not our defect; an ESC in a name or a grid key
    # prints escaped (a code review)
    for name, said in (("a\x00b.json", "folder or below it"), ("\x1b[2Km.json", "\\u001b[2Km")):
        (tmp_path / "sub" / "spec.json").write_text(
            json.dumps({"base": {"file": name}, "grid": grid})
        )
        with pytest.raises(DesignError, match=re.escape(said)):
            sweep.load_spec(tmp_path / "sub" / "spec.json")
    with pytest.raises(DesignError, match=re.escape("grid.cam.\\u001b[2Kx: no such field")):
        sweep.parse_spec(json.dumps({"grid": {"cam.\x1b[2Kx": [10]}}))


def test_csv_holds_the_table_s_columns_and_defuses_formulas():
    """csv_text: the columns of the Parquet table in first-seen order, floats that read
    back exactly, None as empty, and a text a spreadsheet would run as a formula
    (OWASP's CSV injection: "=", "+", "-", "@" first) made plain text by an apostrophe."""
    import csv
    import io

    rows = [
        {"grid.x": 0.1 + 0.2, "design": '=HYPERLINK("http://x")', "valid": True},
        {"grid.x": -1e-300, "design": "@SUM(A1)", "valid": False, "error": "no, -3 mm"},
        {"grid.x": float("inf"), "design": "plain", "valid": None},
    ]
    table = list(csv.reader(io.StringIO(sweep.csv_text(rows))))
    assert table[0] == ["grid.x", "design", "valid", "error"]
    assert [float(r[0]) for r in table[1:]] == [0.1 + 0.2, -1e-300, float("inf")]
    assert [r[1] for r in table[1:]] == ['\'=HYPERLINK("http://x")', "'@SUM(A1)", "plain"]
    assert [r[2] for r in table[1:]] == ["True", "False", ""]
    assert [r[3] for r in table[1:]] == ["", "no, -3 mm", ""]  # (not first: left alone)
    assert sweep.csv_text([{"a": "-1"}, {"a": "+1"}, {"a": "\tx"}]).splitlines()[1:] == [
        "'-1",
        "'+1",
        "'\tx",
    ]


def test_explore_s_spec_is_what_camcore_sweep_runs():
    """The SPEC the Explore tab hands over: camcore sweep parses it to the very points
    (values and order) the tab ran, around the same base design."""
    from camcore.explore import grid_points, spec_document, sweep_grid
    from camcore.model import load_preset

    base = load_preset("paper_example").model_dump(mode="json")
    grid = sweep_grid(
        ("cam.base_radius_mm", 70.0, 90.3), ("follower.offset_mm", 35.0, 25.0), 7, ["a", "b"]
    )
    points = grid_points(grid)
    assert len(points) == 2 * 7 * 7 and points[0]["follower.offset_mm"] == 35.0
    assert [p["follower.kind"] for p in points[:49]] == ["a"] * 49  # kinds slowest
    assert points[1]["cam.base_radius_mm"] == 70.0 and points[7]["cam.base_radius_mm"] > 70
    grid["follower.kind"] = ["single_roller", "double_concave"]
    spec = sweep.parse_spec(spec_document(base, grid))
    assert list(spec.points()) == grid_points(grid)
    assert spec.base == json.loads(load_preset("paper_example").model_dump_json())


def test_the_map_finds_every_front_number_and_keeps_its_labels_apart():
    """A designer's review of the narrow panel: numbers of the front printed over one
    another were left out (list entry 17 was nowhere on the map), the two maps' x
    labels ran into one ("...[mm]Base radius..."), and the legend covered designs.
    Now close numbers share a label ("16,17", "3-5"), each offered number is on the
    map once, the labels stand apart and the legend is below the axes."""
    from camcore.explore import (
        PANEL_PX,
        explore_figure,
        grid_points,
        numbers_text,
        offered,
        pareto,
        sweep_grid,
    )
    from camcore.explore import figure_values as values_of
    from camcore.model import load_preset

    assert numbers_text([3, 4, 5, 9]) == "3-5,9" and numbers_text([16, 17]) == "16,17"
    data = load_preset("paper_example").model_dump(mode="json")
    data["motion"].update(lift_mm=20, rise_deg=120, high_dwell_deg=60, fall_deg=120)
    data["cam"].update(speed_rpm=300)
    kinds = ["single_roller", "double_roller", "single_concave", "double_concave"]
    x, y = ("cam.base_radius_mm", 10.0, 38.0), ("follower.roller_radius_mm", 4.0, 12.0)
    rows = sweep.fast_rows(data, grid_points(sweep_grid(x, y, 8, kinds)))
    names = ["cam_size", "stress", "pressure_angle"]  # (its colour bar narrows the maps)
    front = pareto(rows, names)
    listed = len(offered(front, values_of(rows, names)))
    axes = ((x[0], "Base radius r_b [mm]"), (y[0], "Roller radius r_c [mm]"))
    fig = explore_figure(rows, *axes, names, front, PANEL_PX)
    pareto_ax = fig.axes[len(kinds)]
    labels = [t.get_text() for t in pareto_ax.texts]
    numbers = []
    for label in labels:
        for part in label.split(","):
            lo, _, hi = part.partition("-")
            numbers += range(int(lo), int(hi or lo) + 1)
    assert sorted(numbers) == list(range(1, listed + 1)) and len(labels) < listed
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    r = canvas.get_renderer()
    left, right = (fig.axes[i].xaxis.label.get_window_extent(r) for i in (2, 3))
    assert left.x1 < right.x0  # (the bottom maps' x labels)
    legend = pareto_ax.get_legend().get_window_extent(r)
    assert legend.y1 < pareto_ax.get_window_extent(r).y0  # below the designs


def test_the_nearest_longest_dwell_takes_up_the_turn():
    """explore.balance_for on the double-indexing cam (rise 60, dwell 50, fall 60,
    dwell 10, twice): each rise and fall is balanced by its own cycle's 50 deg dwell
    (a review: the first cycle's fall had moved the second cycle's dwell), the one
    after it where two are as near; none for a classic program's field."""
    from camcore.explore import balance_for, segment_angle_paths
    from camcore.model import load_preset

    d = load_preset("double_index")
    got = [balance_for(d, [f"motion.segments.{i}.angle_deg"]) for i in (0, 2, 4, 6)]
    assert got == [f"motion.segments.{i}.angle_deg" for i in (1, 1, 5, 5)]
    assert balance_for(d, ["cam.base_radius_mm"]) is None
    assert segment_angle_paths(load_preset("paper_example")) == {}  # (classic: its fields)


@pytest.mark.parametrize("third", [None, "pressure_angle"])
def test_each_front_number_stands_at_its_own_design(third):
    """A user's review of an indexer's sweep: the map's "11-14" stood on designs 11-12,
    and 13-14, 7 mm of R away, had no number. A label holds only designs at one spot
    (within a line of text), stands by them, and overprints no other label; with a
    third figure too, whose colour bar narrows the axes (a review: labels measured
    before it overprinted three others)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from camcore.explore import PANEL_PX, explore_figure, figure_values, offered, pareto
    from camcore.explore import grid_points as points_of
    from camcore.explore import sweep_grid as grid_of
    from camcore.model import load_preset

    base = json.loads(load_preset("double_index").model_dump_json())
    kinds = ["single_roller", "double_roller", "single_concave", "double_concave"]
    x, y = ("motion.segments.4.angle_deg", 42.0, 78.0), ("cam.base_radius_mm", 56.0, 104.0)
    points = points_of(grid_of(x, y, 8, kinds), base, "motion.segments.5.angle_deg")
    rows = sweep.fast_rows(base, points)
    names = ["cam_size", "stress", *([third] if third else [])]
    front = pareto(rows, names)
    v = figure_values(rows, names)
    listed = offered(front, v)
    v = v[:, :2]  # (the map's plane)
    fig = explore_figure(rows, (x[0], "Segment 5"), (y[0], "r_b"), names, front, PANEL_PX)
    ax = fig.axes[len(kinds)]
    span = np.ptp(v[front], axis=0)
    seen = []
    for t in ax.texts:
        for part in t.get_text().split(","):
            lo, _, hi = part.partition("-")
            for n in range(int(lo), int(hi or lo) + 1):
                seen.append(n)
                assert np.abs((v[listed[n - 1]] - t.xy) / span).max() < 0.05, (t.get_text(), n)
    assert sorted(seen) == list(range(1, len(listed) + 1))
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    boxes = [t.get_window_extent(canvas.get_renderer()) for t in ax.texts]
    assert not any(a.overlaps(b) for k, a in enumerate(boxes) for b in boxes[k + 1 :])
    # ... and stays in the image (a review: "4-6" cut at its right edge)
    assert all(fig.bbox.x0 <= b.x0 and b.x1 <= fig.bbox.x1 for b in boxes)


def test_the_smallest_cam_each_follower_allows():
    """A designer's review sized a 20 mm / 120 deg packaging cam at 300 rpm on a 1 mm
    grid of r_b: the smallest valid base radius is 17 mm for the single roller (tan phi
    = S'/(r_b + r_c + S): 29.46 deg there, over 30 at 16 mm, by hand), 12 mm for the
    double rollers (phi = asin(e / (r_b + r_c)) = 30 deg exactly), 16 and 15 mm for the
    concave faces (these two are camcore's own figures, kept as a regression check, not
    derived independently). best_per_kind reads them off the rows, one per follower."""
    from camcore.explore import best_per_kind
    from camcore.model import load_preset

    data = load_preset("paper_example").model_dump(mode="json")
    data["motion"].update(lift_mm=20, rise_deg=120, high_dwell_deg=60, fall_deg=120)
    data["cam"].update(speed_rpm=300)
    kinds = ["single_roller", "double_roller", "single_concave", "double_concave"]
    points = [
        {"follower.kind": k, "cam.base_radius_mm": float(r)} for k in kinds for r in range(10, 21)
    ]
    rows = sweep.fast_rows(data, points)
    best = best_per_kind(rows, "cam_size")
    assert list(best) == kinds
    smallest = {k: rows[i]["grid.cam.base_radius_mm"] for k, i in best.items()}
    assert smallest == {
        "single_roller": 17.0,
        "double_roller": 12.0,
        "single_concave": 16.0,
        "double_concave": 15.0,
    }
    assert best_per_kind([{**r, "valid": False} for r in rows], "cam_size") == {}
    # the single roller's by hand: the cycloidal rise's largest tan phi = S' / (R0 + S)
    x = np.linspace(0.0, 1.0, 200001)
    h, beta = 20.0, math.radians(120.0)
    S = h * (x - np.sin(2 * np.pi * x) / (2 * np.pi))
    dS = h / beta * (1 - np.cos(2 * np.pi * x))
    r_c = data["follower"]["roller_radius_mm"]
    phi = {r: np.degrees(np.arctan(dS / (r + r_c + S))).max() for r in (16.0, 17.0)}
    assert phi[16.0] > 30.0 > phi[17.0]


def test_pareto_names_the_least_figure_per_follower(tmp_path, capsys):
    """camcore pareto says, per follower, the valid row least in the first figure: the
    same rows best_per_kind picks from the rows themselves (the review's job: 17, 12,
    16 and 15 mm), the ignored fields as null."""
    from camcore.cli import main
    from camcore.explore import best_per_kind, table_front
    from camcore.model import load_preset

    data = load_preset("paper_example").model_dump(mode="json")
    data["motion"].update(lift_mm=20, rise_deg=120, high_dwell_deg=60, fall_deg=120)
    data["cam"].update(speed_rpm=300)
    kinds = ["single_roller", "double_roller", "single_concave", "double_concave"]
    grid = {
        "follower.kind": kinds,
        "cam.base_radius_mm": {"from": 10, "to": 20, "num": 11},
        "follower.roller_radius_mm": [8.0],
    }
    spec = sweep.parse_spec(json.dumps({"base": data, "grid": grid}))
    path = tmp_path / "r.parquet"
    sweep.run(spec, path, fast=True, progress=None)
    rows = rows_of(path)
    f = table_front(path, ["cam_size", "stress"])
    assert {k: d["row"] for k, d in f.least.items()} == best_per_kind(rows, "cam_size")
    assert [d["grid"]["cam.base_radius_mm"] for d in f.least.values()] == [17, 12, 16, 15]
    assert f.least["single_concave"]["grid"]["follower.roller_radius_mm"] is None
    assert main(["pareto", str(path), "--figures", "cam_size,stress"]) == 0
    out = capsys.readouterr().out
    assert "least cam size R (high-dwell radius) per follower:" in out
    assert "  double_roller: " in out and "cam.base_radius_mm 12" in out


def test_a_balance_segment_takes_up_the_turn(tmp_path):
    """A designer's review swept an indexer's rise angle: 4 of 6 points were no design
    (the program must fill 360 deg). With "balance" the named dwell takes up the turn:
    every point is a design, its row records the dwell's angle as a grid column, the
    rows equal single reports, and the table's SPEC gives each row's design back."""
    grid = {"motion.segments.0.angle_deg": [70.0, 90.0, 110.0], "cam.base_radius_mm": [60, 80]}
    loose = sweep.parse_spec(json.dumps({"base": {"preset": "indexer_345"}, "grid": grid}))
    assert (
        sum(
            r["valid"] is False and bool(r["error"])
            for r in sweep.run_chunk(loose.base, list(loose.points()), verify=False)
        )
        == 4
    )  # (90 deg alone fills the turn)
    text = {
        "base": {"preset": "indexer_345"},
        "grid": grid,
        "balance": "motion.segments.3.angle_deg",
    }
    spec = sweep.parse_spec(json.dumps(text))
    points = list(spec.points())
    assert [p["motion.segments.3.angle_deg"] for p in points[::2]] == [110.0, 90.0, 70.0]
    assert [spec.point(i) for i in range(spec.size)] == points
    path = tmp_path / "r.parquet"
    sweep.run(spec, path, verify=False, progress=None)
    rows = rows_of(path)
    assert all(r["error"] is None for r in rows)
    assert [r["grid.motion.segments.3.angle_deg"] for r in rows[::2]] == [110.0, 90.0, 70.0]
    for i in (0, 5):
        design = sweep.design_of_row(path, i)
        assert [g.angle_deg for g in design.motion.segments] == [
            rows[i]["grid.motion.segments.0.angle_deg"],
            90.0,
            90.0,
            rows[i]["grid.motion.segments.3.angle_deg"],
        ]
        assert rows[i] == sweep.row(spec.base, points[i], verify=False)
    for bad, why in (
        ("motion.segments.9.angle_deg", "no segment 9"),
        ("motion.segments.0.angle_deg", "set by the grid itself"),
        ("motion.rise_deg", "a segment angle"),
    ):
        with pytest.raises(DesignError, match=why):
            sweep.parse_spec(json.dumps({**text, "balance": bad}))
    classic = {"grid": {"motion.rise_deg": [90, 100]}, "balance": "motion.segments.3.angle_deg"}
    with pytest.raises(DesignError, match="low dwell takes up the turn"):
        sweep.parse_spec(json.dumps(classic))


def test_a_front_number_at_the_axes_edge_stays_in_the_image():
    """A teacher's review: the front's last label, "4-6", at the largest cam of the
    sweep, ran off the image's right edge. A label goes to whichever side keeps it in
    the axes."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from camcore.explore import PANEL_PX, explore_figure, pareto
    from camcore.explore import grid_points as points_of
    from camcore.explore import sweep_grid as grid_of
    from camcore.model import load_preset

    base = json.loads(load_preset("paper_example").model_dump_json())
    kinds = ["single_roller", "double_roller", "single_concave", "double_concave"]
    x, y = ("cam.base_radius_mm", 28.0, 52.0), ("follower.offset_mm", 7.0, 13.0)
    rows = sweep.fast_rows(base, points_of(grid_of(x, y, 4, kinds), base, None))
    names = ["cam_size", "stress"]
    fig = explore_figure(rows, (x[0], "r_b"), (y[0], "e"), names, pareto(rows, names), PANEL_PX)
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    ax = fig.axes[len(kinds)]
    boxes = [t.get_window_extent(canvas.get_renderer()) for t in ax.texts]
    assert boxes and all(ax.bbox.x0 <= b.x0 and b.x1 <= ax.bbox.x1 for b in boxes)


def test_the_app_and_the_cli_number_one_front_alike():
    """A review: designs on the front whose stress differed by round-off (115.06532248048867
    and ...822 MPa at one cam size) came in one order in the app's list and in another
    in `camcore pareto`, so `--design 10` was not the app's #10. Both take the order of
    front_order: figures equal to 12 digits are equal, then by row."""
    from camcore.sweep import front_order

    values = np.array([[86.65, 115.06532248048867], [90.0, 100.0], [86.65, 115.06532248048822]])
    assert front_order(values, np.array([0, 2, 1])).tolist() == [0, 2, 1]
    assert front_order(values, np.array([2, 0, 1])).tolist() == [0, 2, 1]


def test_our_local_cluster_does_not_log_the_chunks_ctrl_c_cancels():
    """After Ctrl-C on a --workers run, each running chunk's cancellation was logged
    as a worker WARNING under the clean 'interrupted: ... kept' message."""
    pytest.importorskip("dask.distributed")
    import logging

    def level():
        return logging.getLogger("distributed.worker.state_machine").getEffectiveLevel()

    with sweep._cluster(1, None) as client:
        assert set(client.run(level).values()) == {logging.ERROR}


def test_ctrl_c_at_the_terminal_reaches_the_sweep_alone(tmp_path):
    """Ctrl-C at a terminal is SIGINT to the whole process group: each worker of a
    --workers run printed a KeyboardInterrupt traceback after the clean 'interrupted'
    line (a review). Our workers start with SIGINT ignored; the command alone hears it,
    says what it keeps, and exits 130."""
    pytest.importorskip("dask.distributed")
    import os
    import signal
    import time

    grid = {"cam.base_radius_mm": {"from": 60, "to": 110, "num": 400}}
    (tmp_path / "spec.json").write_text(json.dumps({"grid": grid}))
    cmd = [sys.executable, "-m", "camcore", "sweep", "spec.json", "--out", "r.parquet"]
    run = subprocess.Popen(
        [*cmd, "--workers", "1", "--chunk", "2", "--no-verify"],
        cwd=tmp_path,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,  # its own process group, as a terminal's job
    )
    assert run.stderr is not None
    seen = ""
    deadline = time.monotonic() + 120
    while "designs" not in seen and time.monotonic() < deadline:  # a chunk is done
        seen += os.read(run.stderr.fileno(), 4096).decode()
    os.killpg(run.pid, signal.SIGINT)
    err = seen + run.stderr.read()
    assert run.wait(60) == 130, err
    assert "the same command resumes" in err
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err
