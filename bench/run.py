"""Run every benchmark module bench/bench_*.py, print one table, keep the results.

    python bench/run.py [--quick] [--slow]

Each module exposes ``run(quick: bool) -> list[dict]`` with rows
{name, median_ms, p10_ms, p90_ms, n, note}. A module that fails to import or to run
is reported in the table and the results file, not fatal. Results go to
bench/results/<YYYY-MM-DD>_<hostname>.md with the machine (CPU model, cores) and the
Python and numpy versions. ``--slow`` also passes slow=True to modules that accept it
(e.g. a minute-long load test).
"""

from __future__ import annotations

import argparse
import datetime as dt
import importlib
import inspect
import os
import platform
import socket
import sys
import time
import traceback
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
KEYS = ("name", "median_ms", "p10_ms", "p90_ms", "n", "note")


def machine() -> dict:
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    import numpy

    try:
        load = " ".join(f"{x:.2f}" for x in os.getloadavg())
    except OSError:
        load = "?"
    return {
        "date": dt.datetime.now().strftime("%Y-%m-%d %H:%M"),
        "host": socket.gethostname(),
        "cpu": cpu,
        "cores": os.cpu_count(),
        "python": platform.python_version(),
        "numpy": numpy.__version__,
        "platform": platform.platform(),
        "load average at start": load,
    }


def run_module(name: str, quick: bool, slow: bool) -> tuple[list[dict], str | None]:
    try:
        mod = importlib.import_module(name)
    except Exception as exc:  # report any import failure
        return [], f"import failed: {type(exc).__name__}: {exc}"
    fn = getattr(mod, "run", None)
    if fn is None:
        return [], "no run() function"
    params = inspect.signature(fn).parameters
    kw = {}
    if "quick" in params:
        kw["quick"] = quick
    if "slow" in params:
        kw["slow"] = slow
    try:
        rows = list(fn(**kw))
    except Exception as exc:  # a broken benchmark must not stop the others
        tb = traceback.format_exc(limit=3).strip().splitlines()[-1]
        return [], f"run failed: {type(exc).__name__}: {exc} ({tb})"
    out = []
    for r in rows:
        out.append({k: r.get(k) for k in KEYS} | {"module": name})
    problem = None if "quick" in params else "run() takes no 'quick' argument; ran its default"
    return out, problem


def _f(x) -> str:
    if x is None:
        return "-"
    if isinstance(x, float):
        return f"{x:.3g}" if x < 100 else f"{x:.0f}"
    return str(x)


def table(rows: list[dict]) -> list[str]:
    head = ["module", "benchmark", "median ms", "p10 ms", "p90 ms", "n", "note"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        lines.append(
            "| "
            + " | ".join(
                [
                    r["module"].removeprefix("bench_"),
                    str(r["name"]),
                    _f(r["median_ms"]),
                    _f(r["p10_ms"]),
                    _f(r["p90_ms"]),
                    _f(r["n"]),
                    str(r["note"] or ""),
                ]
            )
            + " |"
        )
    return lines


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="fewer repetitions (CI smoke run)")
    p.add_argument("--slow", action="store_true", help="also the long variants")
    p.add_argument("--only", help="run only modules whose name contains this")
    p.add_argument("--out", type=Path, default=HERE / "results", help="results folder")
    args = p.parse_args(argv)

    sys.path.insert(0, str(HERE))
    sys.path.insert(0, str(ROOT))
    info = machine()
    mods = sorted(f.stem for f in HERE.glob("bench_*.py"))
    if args.only:
        mods = [m for m in mods if args.only in m]
    rows, problems = [], []
    t0 = time.perf_counter()
    for m in mods:
        print(f"running {m} ...", file=sys.stderr, flush=True)
        t = time.perf_counter()
        r, problem = run_module(m, args.quick, args.slow)
        rows += r
        if problem:
            problems.append(f"{m}: {problem}")
            print(f"  {m}: {problem}", file=sys.stderr)
        print(f"  {m}: {len(r)} rows in {time.perf_counter() - t:.1f} s", file=sys.stderr)
    total = time.perf_counter() - t0

    lines = table(rows)
    print("\n".join(lines))
    for pr in problems:
        print(f"PROBLEM {pr}")

    args.out.mkdir(parents=True, exist_ok=True)
    day = info["date"][:10]
    path = args.out / f"{day}_{info['host']}.md"
    mode = "quick" if args.quick else "full"
    md = [f"# Benchmarks {info['date']} on {info['host']}", ""]
    md += [f"- {k}: {v}" for k, v in info.items()]
    md += [
        f"- mode: {mode}{' + slow' if args.slow else ''}",
        f"- modules: {', '.join(mods) or 'none'}",
        f"- wall time: {total:.1f} s",
        "",
    ]
    md += lines
    if problems:
        md += ["", "## Problems", ""] + [f"- {pr}" for pr in problems]
    path.write_text("\n".join(md) + "\n")
    print(f"wrote {path.relative_to(ROOT) if path.is_relative_to(ROOT) else path}")
    return 1 if problems and not rows else 0


if __name__ == "__main__":
    sys.exit(main())
