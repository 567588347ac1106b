"""Command line: ``camcore report | compare | export | sweep | pareto | presets | fields``.

Exit status (the same for every command, so scripts can rely on it):

- 0: the design was analysed and meets every limit (files written, if asked);
- 1: the design was analysed and breaks a limit: the report (text or JSON) is
  still printed, exports are still written, and the limits are listed;
- 2: bad input (unreadable or invalid design file, bad value, impossible export):
  one line starting with ``camcore: error:`` on stderr, never a traceback;
- 3: an internal error, a defect of ours: the traceback, then ``camcore: internal
  error``.

``sweep`` exits 0 when its table is written (each row has its own verdict), 130
when interrupted, by Ctrl-C or by a Dask cluster that lost a chunk for good (the same
command resumes), and 2 on bad input. ``pareto`` exits 0
when it finds a front, 1 when no valid design has the figures, 2 on bad input.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys

import numpy as np

from . import package_version
from .model import (
    PAPER_FOLLOWERS,
    Design,
    DesignError,
    FollowerKind,
    defaulted_fields,
    defaults_note,
    load_preset,
    name_follows_kind,
    preset_names,
    read_design,
    set_field,
    with_given,
)

EXIT_VALID, EXIT_BREAKS_LIMITS, EXIT_BAD_INPUT, EXIT_INTERNAL = 0, 1, 2, 3


def _apply_set(data: dict, assignment: str) -> None:
    """Apply one ``--set a.b.c=VALUE`` to the design dict (VALUE parsed as JSON if it can be)."""
    path, sep, raw = assignment.partition("=")
    if not sep:
        raise DesignError(
            f"--set {assignment!r}: expected FIELD.PATH=VALUE, e.g. cam.base_radius_mm=90"
        )
    if raw.strip().lower().lstrip("+-") in ("nan", "inf", "infinity"):  # any spelling
        raise DesignError(
            f"{path.strip()}: {raw.strip()} is not a number a design may hold (it must be finite)"
        )
    try:
        value = json.loads(raw)
    except (ValueError, RecursionError):  # (5000 nested brackets: not a value either)
        value = raw  # a bare word, e.g. follower.kind=double_roller
    set_field(data, path.strip(), value, "--set ")


def _refuse_program_clash(sets: list[str]) -> None:
    """Refuse --set edits of a classic program's field beside one of its segments
    (model.program_clash: one would be lost without a word)."""
    from .files import printable
    from .model import PROGRAM_CLASH, field_path, program_clash

    fields = [field_path(a.partition("=")[0].strip()) for a in sets]
    for i, fa in enumerate(fields):
        for fb in fields[i + 1 :]:
            if program_clash(fa, fb):
                a, b = printable(fa, 120), printable(fb, 120)  # (the user's words)
                raise DesignError(f"--set {a} and --set {b}: {PROGRAM_CLASH}; set one of them")


def _design(args, unused_note: bool = True, kinds: tuple[FollowerKind, ...] = ()) -> Design:
    """The design the arguments name: a file or a preset, --follower, --set (with a
    note for a follower field the design's kind does not use, if ``unused_note``).
    ``kinds``: the followers the command analyses, if others than the design's own
    (their fields left out of the file are named too)."""
    if args.preset is not None and args.design:  # (--preset "" too: a CLI review)
        raise DesignError("give a design file or --preset, not both")
    if args.preset is not None:
        design = load_preset(args.preset)
    elif args.design:
        design, text = read_design(args.design)
    else:
        raise DesignError(f"give a design file or --preset NAME ({', '.join(preset_names())})")
    if getattr(args, "follower", None):
        design = design.with_kind(args.follower)
    sets = list(getattr(args, "set", None) or [])
    if getattr(args, "tolerance_mm", None) is not None:
        sets.append(f"limits.export_tolerance_mm={args.tolerance_mm!r}")
    if getattr(args, "cutter_diameter_mm", None) is not None:
        sets.append(f"cam.cutter_diameter_mm={args.cutter_diameter_mm!r}")
    if sets:
        from .model import design_from_json

        _refuse_program_clash(sets)
        data = json.loads(design.model_dump_json())
        for assignment in sets:
            _apply_set(data, assignment)
        before = design
        design = design_from_json(json.dumps(data))  # strict: "--set x=true" is refused
        design = name_follows_kind(design, before.follower.kind, before.name)
        if unused_note:
            _note_unused(design, sets)
    if args.design:  # said of the design analysed: after --follower and --set
        given = [a.partition("=")[0].strip() for a in sets]
        given += ["follower.kind"] if getattr(args, "follower", None) else []
        left_out = defaulted_fields(with_given(text, given), design, kinds)
        if left_out:
            from .files import printable

            note = defaults_note(left_out, len(left_out))
            print(f"note: {printable(args.design, 200)}: {note}", file=sys.stderr)
    return design


def _note_unused(design: Design, sets: list[str]) -> None:
    """Say which ``--set`` follower fields the design's follower does not use (a
    review: e_s set on a double follower changed nothing, without a word)."""
    kind = design.follower.kind
    for assignment in sets:
        block, _, name = assignment.partition("=")[0].strip().partition(".")
        if block == "follower" and not kind.uses(name):
            print(
                f"note: --set follower.{name}: a {kind.label} follower does not use it",
                file=sys.stderr,
            )


def _report(args) -> int:
    from .analysis import analyze
    from .report import report_text, summary

    documents = {k: p for k in ("html", "pdf") if (p := getattr(args, f"out_{k}", None))}
    _checked_outputs(documents, args.design)  # (a preset too: a review's two "wrote")
    a = analyze(_design(args))
    s = summary(a)
    print(json.dumps(s, indent=2) if args.json else report_text(s, a.design))
    _write(a, documents)
    return _verdict(a, "the report above has the details")


def _verdict(a, details: str = "run `camcore report` for details") -> int:
    """EXIT_VALID, or EXIT_BREAKS_LIMITS with the broken limits named on stderr (a
    script reading only the exit status and stderr learns which)."""
    from .export import warning

    note = warning(a)
    if note is None:
        return EXIT_VALID
    print(f"note: {note}; {details}", file=sys.stderr)
    return EXIT_BREAKS_LIMITS


def _write(a, outputs: dict[str, str]) -> None:
    """Build every requested file first, then write them all or none (a path that
    cannot be written leaves every file, old or new, as it was)."""
    from .export import EXPORTS
    from .files import FileError, write_all_atomic

    blobs = {kind: EXPORTS[kind].write(a) for kind in outputs}
    try:
        write_all_atomic([(path, blobs[kind]) for kind, path in outputs.items()])
    except FileError as exc:
        raise DesignError(str(exc)) from None
    for kind, path in outputs.items():
        print(f"wrote {path} ({len(blobs[kind])} bytes)", file=sys.stderr)


def _refuse_collisions(
    outputs: dict[str, str], input_path: str | None, what: str = "the input design file"
) -> None:
    """Refuse an output naming the input (``what`` it is), or two outputs naming one file."""
    from .files import same_file

    paths = list(outputs.items())
    for i, (k1, p1) in enumerate(paths):
        if input_path and same_file(p1, input_path):
            raise DesignError(f"--{k1} {p1}: that is {what}; refusing to overwrite it")
        for k2, p2 in paths[i + 1 :]:
            if same_file(p1, p2):
                raise DesignError(f"--{k1} and --{k2} name the same file {p1}; give two paths")


def _compare(args) -> int:
    from .report import compare_rows, compare_text

    kinds: tuple[FollowerKind, ...] = PAPER_FOLLOWERS
    if args.followers is not None:  # ("" is no follower, not the default four: a review)
        names = [n.strip() for n in args.followers.split(",") if n.strip()]
        bad = [n for n in names if n not in FollowerKind.__members__]
        if bad or not names:
            raise DesignError(
                f"--followers: unknown {', '.join(bad) or '(empty)'}; "
                f"choose from {', '.join(k.value for k in FollowerKind)}"
            )
        kinds = tuple(FollowerKind(n) for n in dict.fromkeys(names))
    # (every kind's fields: no note for one the design's own kind does not use)
    rows = compare_rows(_design(args, unused_note=False, kinds=kinds), kinds)
    print(json.dumps(rows, indent=2) if args.json else compare_text(rows))
    for r in rows:
        if r["breaks"]:
            print(f"note: {r['follower']} breaks {', '.join(r['breaks'])}", file=sys.stderr)
    return EXIT_VALID if all(r["valid"] for r in rows) else EXIT_BREAKS_LIMITS


def _outputs(args) -> dict[str, str]:
    """The requested output files by export kind, refusing a path used twice or the input."""
    outputs = {k: p for k in EXPORT_FLAGS if (p := getattr(args, f"out_{k}", None)) is not None}
    for k, p in outputs.items():
        if not p:  # (it had been dropped without a word: a CLI review)
            raise DesignError(f"--{k.replace('_', '-')}: an empty file name")
    if not outputs:
        flags = ", ".join(f"--{k.replace('_', '-')}" for k in EXPORT_FLAGS)
        raise DesignError(f"nothing to export: give one or more of {flags} FILE")
    return _checked_outputs(outputs, args.design)


def _checked_outputs(outputs: dict[str, str], design_path: str | None) -> dict[str, str]:
    """``outputs`` (export kind -> path), refusing a path used twice or the input
    design's, with a note for a path whose suffix is not its format's."""
    _refuse_collisions(outputs, design_path)
    from .export import EXPORTS

    for kind, path in outputs.items():  # (a review wrote an STL into x.dxf unawares)
        suffix = EXPORTS[kind].suffix.rpartition(".")[2]
        if kind != "toolpath" and not path.lower().endswith("." + suffix):  # (G-code: many)
            flag = kind.replace("_", "-")
            print(
                f"note: --{flag} {path}: written as .{suffix}, whatever its name", file=sys.stderr
            )
    return outputs


def _export(args) -> int:
    from .analysis import analyze

    design = _design(args)
    outputs = _outputs(args)
    if args.cutter_diameter_mm is not None and not outputs.keys() & CUTTER_OUTPUTS:
        raise DesignError(  # (a maker's review: it had been ignored without a word)
            "--cutter-diameter-mm is the cutter of --toolpath FILE (the design files "
            "--json, --html and --pdf keep it too): give one of them"
        )
    a = analyze(design)
    _write(a, outputs)
    from .export import PART_KINDS, mounting_note

    if outputs.keys() & set(PART_KINDS) and (mount := mounting_note(a)) is not None:
        print(f"note: {mount}", file=sys.stderr)
    return _verdict(a)


CUTTER_OUTPUTS = {"toolpath", "json", "html", "pdf"}  # the outputs the cutter changes
EXPORT_FLAGS = (
    "stl",
    "dxf",
    "dxf_cut",
    "follower_dxf",
    "csv",
    "series",
    "toolpath",
    "json",
    "html",
    "pdf",
)


def _need_pyarrow(what: str) -> None:
    try:
        import pyarrow  # noqa: F401
    except ImportError:
        raise DesignError(f"{what}: pip install 'camdesigner[sweep]'") from None


WORKERS_PER_CORE = 4  # --workers beyond this many per core only share the cores


def _cores() -> int:
    """The cores this process may run on."""
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1


def _sweep(args) -> int:
    _need_pyarrow("camcore sweep writes Parquet")
    from . import sweep

    spec = sweep.load_spec(args.spec)
    if spec.defaulted:  # a base design file leaving inputs out: said, as report does
        left_out = list(spec.defaulted)
        from .files import printable

        base = printable(spec.base_file.name, 80) if spec.base_file is not None else "base"
        note = defaults_note(left_out, len(left_out), f"its base design file {base}")
        print(f"note: {printable(args.spec, 200)}: {note}", file=sys.stderr)
    most = WORKERS_PER_CORE * _cores()
    if args.workers is not None and not 1 <= args.workers <= most:
        raise DesignError(  # (a review: --workers 5000 started 5000 processes on 2 cores)
            f"--workers {args.workers}: from 1 to {most} ({WORKERS_PER_CORE} for each of "
            f"this machine's {_cores()} cores; more machines: --scheduler ADDRESS)"
        )
    if not 1 <= args.chunk <= sweep.MAX_CHUNK:  # (memory: ~2 MB a design at 0.1 deg)
        raise DesignError(f"--chunk: from 1 to {sweep.MAX_CHUNK} designs")
    if args.workers is not None and args.scheduler is not None:
        raise DesignError("--workers starts a cluster, --scheduler uses one: give one of them")
    _refuse_collisions({"out": args.out}, args.spec, "the sweep's spec file")
    if spec.base_file is not None:  # (a review: the table had replaced the base design)
        _refuse_collisions({"out": args.out}, str(spec.base_file), "the spec's base design file")
    n = sweep.run(
        spec,
        args.out,
        chunk=args.chunk,
        verify=not (args.no_verify or args.fast),
        fast=args.fast,
        workers=args.workers,
        scheduler=args.scheduler,
    )
    print(f"wrote {args.out} ({n} design{'' if n == 1 else 's'}: {sweep.tally(args.out)})")
    return EXIT_VALID


SHOWN_LIMITS = 8  # first broken limits a pareto summary names, the commonest first


def _figure_names(text: str) -> list[str]:
    """--figures a,b,c: known and distinct figure names."""
    from .explore import FIGURES

    names = [n.strip() for n in text.split(",") if n.strip()]
    unknown = [n for n in names if n not in FIGURES]
    if unknown or not names or len(set(names)) != len(names):
        raise DesignError(f"--figures {text!r}: one or more distinct names of {', '.join(FIGURES)}")
    return names


def _presets(args) -> int:
    """The shipped presets, a line each: the name --preset takes, and what it is (a
    designer's review: their names were only in report's --help)."""
    from .model import load_preset, preset_names

    for name in preset_names():
        d = load_preset(name)
        print(f"{name:<20}  {d.name}")
    return EXIT_VALID


def _fields(args) -> int:
    """Every field a design file or --set can give: path, default, range, meaning."""
    from .model import field_table

    rows = field_table()
    if args.json:
        print(json.dumps(rows, indent=2))
        return EXIT_VALID
    for r in rows:
        default = "-" if r["default"] is None else r["default"]
        print(f"{r['path']} = {default}" + (f"   ({r['range']})" if r["range"] else ""))
        if r["description"]:
            print(f"    {r['description']}")
        if r["followers"] is not None:
            print(f"    used by: {', '.join(r['followers']) or 'none'}")
    return EXIT_VALID


def _nulled(value):
    """``value`` with every float that is not finite as None: strict JSON, whatever a
    table holds (a review: an infinite grid value in a hand-edited table crashed
    ``pareto --json``)."""
    if isinstance(value, dict):
        return {k: _nulled(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_nulled(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _pareto(args) -> int:
    _need_pyarrow("camcore pareto reads Parquet")
    from .explore import FIGURES, table_front

    names = _figure_names(args.figures)
    if args.top < 1:
        raise DesignError("--top: at least 1")
    f = table_front(args.table, names)
    if args.design is not None:
        return _front_design(args.table, f, args.design)
    if args.json:
        doc = _nulled({"figures": names, **vars(f)})  # (a hand-edited table's inf: null)
        print(json.dumps(doc, indent=1, allow_nan=False))
        return EXIT_VALID if f.front else EXIT_BREAKS_LIMITS
    broken = f.rows - f.valid - f.refused
    print(
        f"{args.table}: {_count(f.rows, 'row')}: {f.valid} valid, {broken} break a limit, "
        f"{f.refused} not designs"
    )
    if f.first_limits:
        most = list(f.first_limits.items())[:SHOWN_LIMITS]
        more = len(f.first_limits) - len(most)
        print(
            "first limit broken: "
            + ", ".join(f"{code} {n}" for code, n in most)
            + (f" and {more} more" if more else "")
        )
    if f.lacking:
        why = f" ({'; '.join(f.lacking_why)})" if f.lacking_why else ""
        # each figure a row lacks, with how many lack it (a review had read "without a
        # value for cam_size, stress" as both missing where only the stress was)
        which = ", ".join(f"{n} missing in {k}" for n, k in f.lacking_by.items())
        print(f"{_count(f.lacking, 'valid row')} left out: {which}{why}")
    if not f.front:
        print("no valid design with these figures: no Pareto front")
        return EXIT_BREAKS_LIMITS
    if not f.profile_checked:
        print(
            "valid rows from the batched core (sweep --fast): the profile's checks and the "
            "geometric check run when a design is analysed alone (camcore report)"
        )
    if f.least:  # (a review: "the smallest cam each follower allows" took many sweeps)
        first = FIGURES[names[0]]
        print(f"least {first.label} per follower:")
        for kind, d in f.least.items():
            fields = ", ".join(
                f"{_cell(k)} {_cell(v)}" for k, v in d["grid"].items() if k != "follower.kind"
            )
            print(f"  {_cell(kind)}: {d['value']:.4g} {first.unit} (row {d['row']}: {fields})")
    again = f" (and {_count(f.repeats, 'repeat')} in a field its follower ignores)"
    print(
        f"Pareto front of {', '.join(FIGURES[n].label for n in names)} over the valid "
        f"designs, smaller is better: {_count(len(f.front), 'design')}"
        + (again if f.repeats else "")
    )
    grid = list(dict.fromkeys(k for d in f.front for k in d["grid"]))
    head = ["#", *map(_cell, grid), *(f"{FIGURES[n].label} [{FIGURES[n].unit}]" for n in names)]
    shown = f.front[: args.top]
    table = [
        [
            str(i),
            *(_cell(d["grid"].get(k)) for k in grid),
            *(f"{d['figures'][n]:.4g}" for n in names),
        ]
        for i, d in enumerate(shown, start=1)
    ]
    widths = [max(len(c) for c in col) for col in zip(head, *table, strict=True)]
    for line in [head, *table]:
        print("  ".join(c.ljust(w) for c, w in zip(line, widths, strict=True)).rstrip())
    if len(shown) < len(f.front):
        print(f"({len(shown)} of {len(f.front)} shown; --top N or --json for more)")
    return EXIT_VALID


def _front_design(table: str, f, number: int) -> int:
    """Print design ``number`` of the front (1-based, as listed) as design JSON."""
    from .model import design_to_json
    from .sweep import design_of_row

    if not 1 <= number <= len(f.front):
        raise DesignError(f"--design {number}: the front lists designs 1 to {len(f.front)}")
    print(design_to_json(design_of_row(table, f.front[number - 1]["row"])))
    return EXIT_VALID


def _count(n: int, noun: str) -> str:
    return f"{n} {noun}" + ("" if n == 1 else "s")


def _cell(value) -> str:
    """A grid value (or field name) in the front's table; '-' for a field the follower
    does not use. Text is printable (a table is a file from anywhere: an ESC in a
    column name had reached the terminal, a security review)."""
    from .files import printable

    if value is None:
        return "-"
    return f"{value:g}" if isinstance(value, float) else printable(str(value), 60)


def _parser() -> argparse.ArgumentParser:
    from .export import EXPORTS

    p = argparse.ArgumentParser(
        prog="camcore",
        description="Disk cam design after Chuang, Hsu & Chang (translating followers).",
        epilog="Exit status: 0 valid, 1 analysed but breaks a limit, 2 bad input, 3 a defect "
        "of ours (please report it) "
        "(sweep: 0 table written, 130 interrupted, 2 bad input; pareto: 0 a front found, "
        "1 no valid design with the figures, 2 bad input).",
    )
    p.add_argument("--version", action="version", version=f"%(prog)s {package_version()}")
    sub = p.add_subparsers(dest="command", required=True)

    def source(sp, follower=True):
        sp.add_argument("design", nargs="?", help="design JSON file")
        sp.add_argument("--preset", help=f"a preset instead of a file: {', '.join(preset_names())}")
        if follower:
            sp.add_argument(
                "--follower",
                choices=[k.value for k in FollowerKind],
                help="override the follower kind",
            )
        sp.add_argument(
            "--set",
            action="append",
            metavar="FIELD=VALUE",
            help="override one design field, e.g. --set cam.base_radius_mm=90 "
            "(repeatable; VALUE is JSON, or a bare word for names)",
        )

    ps = sub.add_parser("presets", help="list the shipped designs --preset takes")
    ps.set_defaults(run=_presets)

    fl = sub.add_parser("fields", help="list every design field (--set PATH=VALUE, design files)")
    fl.add_argument("--json", action="store_true", help="print JSON rows")
    fl.set_defaults(run=_fields)

    r = sub.add_parser("report", help="analyse one design")
    source(r)
    r.add_argument("--json", action="store_true", help="print one JSON object")
    r.add_argument(
        "--html",
        dest="out_html",
        metavar="FILE",
        help="also write the printable report as self-contained HTML",
    )
    r.add_argument("--pdf", dest="out_pdf", metavar="FILE", help="also write it as PDF")
    r.set_defaults(run=_report)

    c = sub.add_parser("compare", help="followers side by side on one design (Table 1)")
    source(c, follower=False)
    c.add_argument(
        "--followers",
        metavar="KIND,KIND,...",
        help="the followers to compare (default: the paper's four: "
        f"{','.join(k.value for k in PAPER_FOLLOWERS)})",
    )
    c.add_argument("--json", action="store_true", help="print JSON rows")
    c.set_defaults(run=_compare)

    e = sub.add_parser("export", help="write STL / DXF / CSV / design JSON")
    source(e)
    for kind in EXPORT_FLAGS:
        flag = f"--{kind.replace('_', '-')}"
        names = (flag, "--angles") if kind == "series" else (flag,)  # (its old name)
        e.add_argument(*names, dest=f"out_{kind}", metavar="FILE", help=EXPORTS[kind].help)
    e.add_argument(
        "--tolerance-mm",
        type=float,
        metavar="MM",
        help="largest distance of the exported polyline from the exact cam "
        "(default: the design's limits.export_tolerance_mm, 0.001 mm)",
    )
    e.add_argument(
        "--cutter-diameter-mm",
        type=float,
        metavar="D",
        help="end mill for --toolpath (default: cam.cutter_diameter_mm, 10 mm)",
    )
    e.set_defaults(run=_export)

    w = sub.add_parser("sweep", help="analyse a grid of designs into one Parquet table")
    w.add_argument(
        "spec",
        help='sweep JSON: {"base": {...} | {"preset": NAME} | {"file": NAME}, "grid": '
        '{"cam.base_radius_mm": [60, 70] | {"from", "to", "num"}}}',
    )
    w.add_argument("--out", required=True, metavar="FILE", help="Parquet file to write")
    w.add_argument(
        "--workers", type=int, metavar="N", help="run on a local Dask cluster of N worker processes"
    )
    w.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="run on an existing Dask cluster, e.g. tcp://host:8786",
    )
    w.add_argument(
        "--chunk",
        type=int,
        default=32,
        metavar="N",
        help="designs per unit of work (default 32, at most 512)",
    )
    w.add_argument(
        "--no-verify",
        action="store_true",
        help="skip the geometric check (faster; verification.max_lift_error_mm is empty)",
    )
    w.add_argument(
        "--fast",
        action="store_true",
        help="the batched core: designs that differ only in their geometry are analysed "
        "together (many times faster); the report's fixed-size figures and the paper's "
        "limits, no profile figures, wear or geometric check (column profile_checked); "
        "a design with a bore, a diameter limit or contact friction on a sliding face "
        "gets the full analysis",
    )
    w.set_defaults(run=_sweep)

    from .explore import FIGURES

    f = sub.add_parser("pareto", help="the Pareto front of a sweep's table")
    f.add_argument("table", help="a Parquet table written by camcore sweep")
    f.add_argument(
        "--figures",
        default="cam_size,stress,pressure_angle",
        metavar="NAME,NAME,...",
        help=f"figures to minimize, of {', '.join(FIGURES)} "
        "(default cam_size,stress,pressure_angle)",
    )
    f.add_argument("--top", type=int, default=20, metavar="N", help="designs listed (default 20)")
    f.add_argument("--json", action="store_true", help="print one JSON object, the whole front")
    f.add_argument(
        "--design",
        type=int,
        metavar="N",
        help="print design N of the front (as listed) as a design file, e.g. "
        "> best.json, then camcore report/export best.json",
    )
    f.set_defaults(run=_pareto)
    for sp in sub.choices.values():  # (main names an unknown option's command)
        sp.set_defaults(command_parser=sp)
    return p


def main(argv: list[str] | None = None) -> int:
    from pydantic import ValidationError

    from .export import ExportError
    from .files import FileError
    from .model import format_validation_error
    from .sweep import ClusterLost

    parser = _parser()
    args, extra = parser.parse_known_args(argv)
    if extra:  # the command's own usage and name, not the top level's (a README review)
        args.command_parser.error(f"unrecognized arguments: {' '.join(extra)}")
    try:
        # extreme designs overflow intermediate terms; results are checked finite
        with np.errstate(all="ignore"):
            return args.run(args)
    except (DesignError, ExportError, FileError) as exc:
        print(f"camcore: error: {_shown(str(exc))}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except ValidationError as exc:
        print(f"camcore: error: {_shown(format_validation_error(exc))}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        return 130
    except ClusterLost as exc:  # not ours, nor the input's: the kept chunks resume
        print(f"camcore: interrupted: {_shown(str(exc))}", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return 0
    except Exception as exc:  # a defect of ours: not 1 ("breaks a limit") nor 2 (input)
        import traceback

        traceback.print_exc()
        print(
            f"camcore: internal error ({type(exc).__name__}): please report it with the "
            "command and the design file",
            file=sys.stderr,
        )
        return EXIT_INTERNAL


def _shown(message: str) -> str:
    """An error as the terminal gets it: one line, its non-printable characters as
    \\uXXXX, at most MESSAGE_CHARS (messages quote a file's or a spec's keys and values,
    and an ESC in one had reached the terminal: a review)."""
    from .files import printable

    return printable(message, MESSAGE_CHARS)


MESSAGE_CHARS = 2000


if __name__ == "__main__":
    sys.exit(main())
