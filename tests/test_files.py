"""Hostile design files (issue 4): malformed, huge, absurdly deep, wrong or older schema
version, not JSON at all; given to design_from_json / load_design and to the CLI they
give one clear line and a non-zero exit, never a traceback. Exports of extreme but
valid designs stay watertight (STL) and readable (DXF)."""

from __future__ import annotations

import io
import itertools
import json
import math
import re
import subprocess
import sys
from pathlib import Path

import ezdxf
import numpy as np
import pytest
import trimesh

from camcore import cli
from camcore.analysis import analyze
from camcore.export import ExportError, dxf_bytes, stl_bytes
from camcore.model import (
    MAX_DESIGN_BYTES,
    Design,
    DesignError,
    FollowerKind,
    MotionLaw,
    design_from_json,
    design_to_json,
    load_design,
)

GOOD = json.loads(design_to_json(Design()))


def _doc(**parts) -> str:
    d = json.loads(json.dumps(GOOD))
    for k, v in parts.items():
        d[k] = v
    return json.dumps(d)


# name -> (file bytes, words the one-line message must contain)
BAD_FILES: dict[str, tuple[bytes, tuple[str, ...]]] = {
    "empty": (b"", ("JSON",)),
    "whitespace": (b" \n\t ", ("JSON",)),
    "truncated": (design_to_json(Design())[:-40].encode(), ("JSON",)),
    "trailing_garbage": (design_to_json(Design()).encode() + b" }{", ("JSON",)),
    "single_quotes": (b"{'motion': {}}", ("JSON",)),
    "comment": (b'{"motion": {} // lift\n}', ("JSON",)),
    "list": (b"[1, 2, 3]", ("JSON object",)),
    "string": (b'"a design"', ("JSON object",)),
    "number": (b"42", ("JSON object",)),
    "null": (b"null", ("JSON object",)),
    "binary_random": (
        bytes(np.random.default_rng(4).integers(0, 256, 4096, dtype=np.uint8)),
        ("JSON",),
    ),
    "binary_png": (b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR" + b"\x00" * 64, ("JSON",)),
    "utf16_bom": (design_to_json(Design()).encode("utf-16"), ()),  # decodes or says why
    "latin1": ('{"name": "caf\xe9"}'.encode("latin-1"), ("JSON",)),
    "deep_array": (b"[" * 200_000 + b"]" * 200_000, ("JSON",)),
    "deep_object": (b'{"a":' * 100_000 + b"1" + b"}" * 100_000, ("JSON",)),
    "deep_in_field": (('{"name": ' + "[" * 500 + "]" * 500 + "}").encode(), ("name",)),
    "nan": (_doc(motion={"lift_mm": "NaN"}).replace('"NaN"', "NaN").encode(), ("lift_mm",)),
    "infinity": (
        _doc(cam={"base_radius_mm": 1}).replace(": 1}", ": Infinity}").encode(),
        ("base_radius_mm",),
    ),
    "overflow": (
        _doc(cam={"base_radius_mm": 1}).replace(": 1}", ": 1e999}").encode(),
        ("base_radius_mm",),
    ),
    "huge_int": (
        _doc(cam={"base_radius_mm": 1}).replace(": 1}", ": 1" + "0" * 5000 + "}").encode(),
        ("JSON",),
    ),
    "string_number": (_doc(motion={"lift_mm": "fifteen"}).encode(), ("motion.lift_mm",)),
    "negative": (_doc(cam={"base_radius_mm": -80}).encode(), ("cam.base_radius_mm",)),
    "zero_radius": (_doc(cam={"base_radius_mm": 0}).encode(), ("cam.base_radius_mm",)),
    "subnormal_radius": (_doc(cam={"base_radius_mm": 5e-324}).encode(), ("cam.base_radius_mm",)),
    "extra_field": (
        _doc(cam={"base_radius_mm": 80, "colour": "red"}).encode(),
        ("cam.colour", "Extra"),
    ),
    "extra_part": (_doc(gearbox={}).encode(), ("gearbox",)),
    "wrong_part_type": (_doc(motion=[1, 2]).encode(), ("motion",)),
    "bad_kind": (_doc(follower={"kind": "flat_faced"}).encode(), ("follower.kind",)),
    "dwell_overflow": (_doc(motion={"rise_deg": 200, "fall_deg": 200}).encode(), ("360",)),
    "offset_at_limit": (
        _doc(follower={"kind": "double_roller", "roller_radius_mm": 10, "offset_mm": 90}).encode(),
        ("follower.offset_mm",),
    ),
    "schema_3": (_doc(schema_version=3).encode(), ("schema_version", "3")),
    "schema_0_older": (_doc(schema_version=0).encode(), ("schema_version", "0")),
    "schema_string": (_doc(schema_version="1.0").encode(), ("schema_version",)),
    "schema_null": (_doc(schema_version=None).encode(), ("schema_version",)),
    "long_name": (_doc(name="x" * 10_000).encode(), ("name",)),
    "newline_in_value": (_doc(schema_version="1\n2\n3").encode(), ("schema_version",)),
}


def _huge(tmp_path: Path, size: int) -> Path:
    """A syntactically valid design padded to ``size`` bytes with whitespace."""
    text = design_to_json(Design())
    p = tmp_path / "huge.json"
    with p.open("w") as f:
        f.write(text[:-1])
        f.write(" " * (size - len(text)))
        f.write("}")
    return p


@pytest.mark.parametrize("name", sorted(BAD_FILES))
def test_design_from_json_one_line(name):
    data, words = BAD_FILES[name]
    try:
        design_from_json(data)
    except DesignError as exc:
        msg = str(exc)
    else:
        assert name == "utf16_bom", f"{name} was accepted"
        return
    assert msg and "\n" not in msg, repr(msg)
    assert len(msg) < 2000, f"message of {len(msg)} chars"
    assert "Traceback" not in msg
    for w in words:
        assert w in msg, (w, msg)


@pytest.mark.parametrize("name", sorted(BAD_FILES))
def test_cli_bad_file_one_line_exit_2(name, tmp_path, capsys):
    data, words = BAD_FILES[name]
    p = tmp_path / f"{name}.json"
    p.write_bytes(data)
    code = cli.main(["report", str(p)])
    out, err = capsys.readouterr()
    if name == "utf16_bom" and code == 0:
        return
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("camcore: error: "), err[:500]
    assert "Traceback" not in err
    for w in words:
        assert w in lines[0], (w, lines[0])


@pytest.mark.parametrize("size", [MAX_DESIGN_BYTES + 1, 30_000_000])
def test_huge_files_are_refused_without_reading(size, tmp_path, capsys):
    p = _huge(tmp_path, size)
    with pytest.raises(DesignError, match="bytes"):
        load_design(p)
    assert cli.main(["report", str(p)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "bytes" in err
    # the same text handed over in memory (an upload) is refused before parsing
    with pytest.raises(DesignError, match="limit"):
        design_from_json(p.read_bytes())


def test_huge_but_under_the_limit_loads(tmp_path):
    p = _huge(tmp_path, MAX_DESIGN_BYTES - 10)
    assert load_design(p) == Design()


def test_missing_file_directory_and_device(tmp_path, capsys):
    for target in (tmp_path / "nope.json", tmp_path):
        assert cli.main(["report", str(target)]) == 2
        err = capsys.readouterr().err
        assert err.startswith("camcore: error: ") and err.count("\n") == 1, err


def test_subprocess_binary_file_no_traceback(tmp_path):
    """The real entry point, as a user runs it."""
    p = tmp_path / "cam.stl"
    p.write_bytes(BAD_FILES["binary_random"][0])
    for args in (
        ["report", str(p)],
        ["compare", str(p)],
        ["export", str(p), "--stl", str(tmp_path / "o.stl")],
    ):
        r = subprocess.run(
            [sys.executable, "-m", "camcore.cli", *args], capture_output=True, text=True, timeout=60
        )
        assert r.returncode == 2, r
        assert "Traceback" not in r.stderr
        assert r.stderr.startswith("camcore: error: ") and r.stderr.count("\n") == 1
        assert r.stdout == ""


def test_older_schema_version_says_why(tmp_path):
    """schema_version 0 (before versioning) is refused with the versions named;
    a file without a version is read as the current one."""
    with pytest.raises(DesignError, match=r"format 0, older than any this program can upgrade"):
        design_from_json(_doc(schema_version=0))
    d = json.loads(_doc())
    del d["schema_version"]
    assert design_from_json(json.dumps(d)) == Design()


# --- exports of extreme but valid designs ------------------------------------------------


def _extreme_designs():
    """Tiny and huge cams, each follower kind and each law (pairs rotated so every law
    meets every kind on some size)."""
    laws = list(MotionLaw)
    for (i, kind), (scale, res) in itertools.product(
        enumerate(FollowerKind), [(0.001, 1.0), (1.0, 0.5), (100.0, 1.0)]
    ):
        rb = 80.0 * scale
        law = laws[(i + int(np.log10(scale))) % len(laws)]
        fall = laws[(i + 3) % len(laws)]
        yield (
            f"{kind.value}-{law.value}-{fall.value}-rb{rb:g}",
            {
                "follower": {
                    "kind": kind.value,
                    "roller_radius_mm": min(8.0 * scale, 1000),
                    "face_radius_mm": max(-250.0 * scale, -1e5),
                    "offset_mm": min(10.0 * scale, 1000),
                },
                "motion": {
                    "lift_mm": min(15.0 * scale, 1000),
                    "rise_law": law.value,
                    "fall_law": fall.value,
                },
                "cam": {"base_radius_mm": rb, "width_mm": 15.0 * scale},
                "limits": {"resolution_deg": res},
            },
        )
    yield (
        "lowest_dwell_edges",
        {
            "motion": {
                "rise_deg": 179.99,
                "high_dwell_deg": 0.0,
                "fall_deg": 180.0,
                "lift_mm": 5.0,
            },
            "follower": {"kind": "single_roller"},
            "limits": {"resolution_deg": 0.5},
        },
    )
    yield (
        "min_lengths",
        {
            "cam": {"base_radius_mm": 0.001, "width_mm": 0.001},
            "motion": {"lift_mm": 0.001},
            "follower": {"kind": "single_roller", "roller_radius_mm": 0.001},
            "limits": {"resolution_deg": 1.0},
        },
    )


EXTREME = dict(_extreme_designs())


@pytest.mark.parametrize("name", sorted(EXTREME))
def test_extreme_exports_watertight_stl_and_readable_dxf(name):
    d = Design.model_validate(EXTREME[name])
    a = analyze(d, verify=False)
    try:
        stl = stl_bytes(a)
    except ExportError as exc:  # a self-crossing profile is refused, with the reason
        assert a.violations and "star-shaped" in str(exc)
        # the refusal names what to fix (a review: "the listed violations", listed
        # nowhere): the limits that fold a profile, not the stress or pressure angle
        from camcore.export import FOLDING

        folding = {v.code for v in a.violations if v.code in FOLDING} or {
            v.code for v in a.violations
        }
        tail = str(exc).split("fix these first: ")[1]
        assert set(re.findall(r"(?:^|, )([a-z_]+) \(", tail)) == folding
        pytest.skip(f"refused: {[v.code for v in a.violations]}")
    mesh = trimesh.load(io.BytesIO(stl), file_type="stl")
    assert mesh.is_watertight
    assert mesh.is_winding_consistent
    area_mm2 = a.profile.area * 1e6
    expect = area_mm2 * d.cam.width_mm
    assert mesh.volume > 0
    assert mesh.volume == pytest.approx(expect, rel=1e-6)
    # the mesh has the cam's size
    extent = mesh.bounds[1] - mesh.bounds[0]
    assert extent[2] == pytest.approx(d.cam.width_mm, rel=1e-6)  # STL is float32
    assert extent[0] == pytest.approx(np.ptp(a.profile.points[:, 0]) * 1e3, rel=1e-6)

    dxf = dxf_bytes(a)
    doc = ezdxf.read(io.StringIO(dxf.decode("utf-8")))
    polys = list(doc.modelspace().query("LWPOLYLINE"))
    assert len(polys) == 1 and polys[0].closed
    _outline_holds_the_profile(polys[0], a.profile.points * 1e3)
    auditor = doc.audit()
    assert not auditor.has_errors, [str(e) for e in auditor.errors]


def _outline_holds_the_profile(poly, prof: np.ndarray) -> None:
    """The DXF outline's vertices are profile vertices, and every profile vertex is
    one of them or lies on one of its arcs (a dwell: export.profile_xyb)."""
    from scipy.spatial import cKDTree

    tol = 1e-9 * max(1.0, np.abs(prof).max())
    pts = np.array([p[:2] for p in poly.get_points()])
    assert cKDTree(prof).query(pts)[0].max() < tol
    arcs = [e for e in poly.virtual_entities() if e.dxftype() == "ARC"]
    for x, y in prof[cKDTree(pts).query(prof)[0] >= tol]:
        polar = math.degrees(math.atan2(y, x))
        on = [
            e
            for e in arcs
            if (polar - e.dxf.start_angle) % 360 <= (e.dxf.end_angle - e.dxf.start_angle) % 360
        ]
        assert on and abs(math.hypot(x, y) - on[0].dxf.radius) < tol, (x, y)


def test_extreme_exports_mostly_succeed():
    """Not every extreme design may be refused: most must export."""
    ok = 0
    for data in EXTREME.values():
        a = analyze(Design.model_validate(data), verify=False)
        if a.profile.is_star_shaped():
            ok += 1
    assert ok >= len(EXTREME) * 0.75, ok


def test_cli_export_extreme_design(tmp_path):
    p = tmp_path / "tiny.json"
    p.write_text(json.dumps(EXTREME["min_lengths"]))
    stl, dxf = tmp_path / "t.stl", tmp_path / "t.dxf"
    # a 1 um cam under the default load: the Hertz stress breaks the allowable (exit 1),
    # and the files are still written
    assert cli.main(["export", str(p), "--stl", str(stl), "--dxf", str(dxf)]) == 1
    assert trimesh.load(stl).is_watertight
    ezdxf.readfile(dxf)


def test_a_written_file_keeps_its_mode_or_takes_the_umask_s(tmp_path):
    """A security review: every written file came out 0644, a private 0600 file (under
    umask 077) readable by all after an export over it."""
    import os
    import stat

    from camcore.files import write_all_atomic, write_atomic

    def mode(p):
        return stat.S_IMODE(p.stat().st_mode)

    private, shared = tmp_path / "priv.json", tmp_path / "group.json"
    private.write_bytes(b"old")
    private.chmod(0o600)
    shared.write_bytes(b"old")
    shared.chmod(0o664)
    old = os.umask(0o077)
    try:
        write_all_atomic([(private, b"new"), (shared, b"new"), (tmp_path / "new.csv", b"x")])
        assert (mode(private), mode(shared), mode(tmp_path / "new.csv")) == (0o600, 0o664, 0o600)
        os.umask(0o022)
        write_atomic(tmp_path / "open.csv", b"x")
        assert mode(tmp_path / "open.csv") == 0o644 and private.read_bytes() == b"new"
    finally:
        os.umask(old)
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "group.json",
        "new.csv",
        "open.csv",
        "priv.json",
    ]


def test_a_write_keeps_a_link_and_refuses_a_fifo(tmp_path):
    """A review: ``--out`` on a FIFO or a symbolic link replaced it with a plain file
    (as root, ``--out /dev/stdout`` would have replaced that link). A link's target is
    written, the link kept (as a shell's ``>`` does); a FIFO or a device is refused and
    left as it was, and nothing of a write refused is left behind."""
    import os

    from camcore.files import FileError, write_all_atomic, write_atomic

    target = tmp_path / "real.csv"
    target.write_bytes(b"old")
    link = tmp_path / "latest.csv"
    link.symlink_to(target.name)
    write_atomic(link, b"new")
    assert link.is_symlink() and target.read_bytes() == b"new"
    dangling = tmp_path / "next.csv"
    dangling.symlink_to("made.csv")
    write_atomic(dangling, b"made")
    assert dangling.is_symlink() and (tmp_path / "made.csv").read_bytes() == b"made"
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    with pytest.raises(FileError, match="not a regular file"):
        write_all_atomic([(tmp_path / "first.csv", b"x"), (fifo, b"y")])
    with pytest.raises(FileError, match="under /dev or /proc"):
        write_atomic(_link_to_null(tmp_path), b"x")
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "latest.csv",
        "made.csv",
        "next.csv",
        "null",
        "pipe",
        "real.csv",
    ]


def test_a_write_refuses_a_stream_and_takes_the_longest_name(tmp_path):
    """A CLI review: ``export --json /dev/stdout >> all.log`` lost the log's lines (the
    link led to the file the shell appends to, and the rename replaced it), and a valid
    250-character file name was refused (the temporary name passed 255 bytes)."""
    log = tmp_path / "all.log"
    log.write_bytes(b"kept\n")
    with log.open("ab") as out:
        run = subprocess.run(
            [sys.executable, "-m", "camcore", "export", "--preset", "paper_example"]
            + ["--json", "/dev/stdout"],
            stdout=out,
            stderr=subprocess.PIPE,
            text=True,
        )
    assert run.returncode == 2 and "under /dev or /proc" in run.stderr
    assert log.read_bytes() == b"kept\n"
    from camcore.files import FileError, write_atomic

    link = tmp_path / "out.json"
    link.symlink_to("/proc/self/fd/1")
    with pytest.raises(FileError, match="under /dev or /proc"):
        write_atomic(link, b"x")
    fds = tmp_path / "fds"  # a folder link into /proc (a review of the change)
    fds.symlink_to("/proc/self/fd")
    with pytest.raises(FileError, match="under /dev or /proc"):
        write_atomic(fds / "1", b"x")
    longest = tmp_path / ("a" * 251 + ".stl")  # 255 bytes
    write_atomic(longest, b"solid")
    assert longest.read_bytes() == b"solid"
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        ["all.log", "fds", longest.name, "out.json"]
    )


def _link_to_null(folder):
    """A link to /dev/null (a device: never replaced, whoever runs the test)."""
    link = folder / "null"
    link.symlink_to("/dev/null")
    return link
