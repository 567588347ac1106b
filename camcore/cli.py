"""Command line: ``camcore report | compare | export``.

Every failure (bad file, bad value, impossible export) prints one line starting
with ``camcore: error:`` and exits with status 2; never a traceback.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from .model import Design, DesignError, FollowerKind, load_design, load_preset, preset_names


def _design(args) -> Design:
    if args.preset and args.design:
        raise DesignError("give a design file or --preset, not both")
    if args.preset:
        design = load_preset(args.preset)
    elif args.design:
        design = load_design(args.design)
    else:
        raise DesignError(f"give a design file or --preset NAME ({', '.join(preset_names())})")
    if getattr(args, "follower", None):
        design = design.with_kind(args.follower)
    return design


def _report(args) -> None:
    from .report import analyze_summary, report_text

    s = analyze_summary(_design(args))
    print(json.dumps(s, indent=2) if args.json else report_text(s))


def _compare(args) -> None:
    from .report import compare_rows, compare_text

    rows = compare_rows(_design(args))
    print(json.dumps(rows, indent=2) if args.json else compare_text(rows))


def _export(args) -> None:
    from . import export
    from .analysis import analyze

    design = _design(args)
    outputs = {"stl": args.stl, "dxf": args.dxf, "csv": args.csv, "json": args.json_out}
    if not any(outputs.values()):
        raise DesignError("nothing to export: give --stl, --dxf, --csv and/or --json FILE")
    a = analyze(design)
    writers = {
        "stl": lambda: export.stl_bytes(a),
        "dxf": lambda: export.dxf_bytes(a),
        "csv": lambda: export.csv_text(a).encode(),
        "json": lambda: export.json_text(design).encode(),
    }
    for kind, path in outputs.items():
        if path:
            data = writers[kind]()
            try:
                Path(path).write_bytes(data)
            except OSError as exc:
                raise DesignError(f"cannot write {path}: {exc.strerror}") from None
            print(f"wrote {path} ({len(data)} bytes)")
    if a.violations:
        print(f"note: the design breaks {len(a.violations)} limit(s); run `camcore report`")


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="camcore", description="Disk cam design after Chuang, Hsu & Chang (four followers)."
    )
    sub = p.add_subparsers(dest="command", required=True)

    def source(sp, follower=True):
        sp.add_argument("design", nargs="?", help="design JSON file")
        sp.add_argument("--preset", help=f"a preset instead of a file: {', '.join(preset_names())}")
        if follower:
            sp.add_argument("--follower", choices=[k.value for k in FollowerKind],
                            help="override the follower kind")

    r = sub.add_parser("report", help="analyse one design")
    source(r)
    r.add_argument("--json", action="store_true", help="print one JSON object")
    r.set_defaults(run=_report)

    c = sub.add_parser("compare", help="the four followers on one design (Table 1)")
    source(c, follower=False)
    c.add_argument("--json", action="store_true", help="print JSON rows")
    c.set_defaults(run=_compare)

    e = sub.add_parser("export", help="write STL / DXF / CSV / design JSON")
    source(e)
    e.add_argument("--stl", help="STL file of the cam solid (mm)")
    e.add_argument("--dxf", help="DXF file of the profile (mm)")
    e.add_argument("--csv", help="CSV of the profile points")
    e.add_argument("--json", dest="json_out", help="design JSON file")
    e.set_defaults(run=_export)
    return p


def main(argv: list[str] | None = None) -> int:
    from pydantic import ValidationError

    from .export import ExportError
    from .model import format_validation_error

    args = _parser().parse_args(argv)
    try:
        # extreme designs overflow intermediate terms; results are checked finite
        with np.errstate(all="ignore"):
            args.run(args)
    except (DesignError, ExportError) as exc:
        print(f"camcore: error: {exc}", file=sys.stderr)
        return 2
    except ValidationError as exc:
        print(f"camcore: error: {format_validation_error(exc)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130
    except BrokenPipeError:
        return 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
