"""Benchmarks of camcore: one analysis, the four-follower comparison, the geometric
check, STL/DXF export, how the analysis time grows with the resolution and with
the number of designs analysed in one batch, and the Pareto front of a million-row
sweep (``camcore pareto``) beside the sort it cannot do without.

``run(quick)`` returns rows {name, median_ms, p10_ms, p90_ms, n, note};
``python bench/run.py`` runs it with every other bench module.
"""

from __future__ import annotations

import time

import numpy as np
from rows import row as _row

from camcore.analysis import analyze, compare
from camcore.export import dxf_bytes, stl_bytes
from camcore.model import Design, FollowerKind, load_preset
from camcore.verify import follower_lift, max_lift_error


def _time(fn, n: int, warmup: int = 1) -> np.ndarray:
    for _ in range(warmup):
        fn()
    out = np.empty(n)
    for i in range(n):
        t0 = time.perf_counter()
        fn()
        out[i] = time.perf_counter() - t0
    return out * 1e3


def _with_resolution(design: Design, res: float) -> Design:
    data = design.model_dump()
    data["limits"]["resolution_deg"] = res
    return Design.model_validate(data)


def _batch(n: int) -> list[Design]:
    """n different valid designs (lift and base radius varied around the paper's)."""
    base = load_preset("paper_example").model_dump()
    out = []
    for i in range(n):
        d = {k: dict(v) if isinstance(v, dict) else v for k, v in base.items()}
        d["motion"]["lift_mm"] = 10.0 + 10.0 * i / max(1, n - 1)
        d["cam"]["base_radius_mm"] = 70.0 + 20.0 * ((i * 7) % n) / max(1, n)
        out.append(Design.model_validate(d))
    return out


def run(quick: bool = False) -> list[dict]:
    k = 1 if quick else 4  # repetitions scale
    design = load_preset("paper_example")  # double concave, 0.1 deg
    rows = []
    a = analyze(design, verify=False)
    M, N = a.profile.points.shape[0], a.theta.size
    rows.append(
        _row(
            "analyze 1 follower (verify off)",
            _time(lambda: analyze(design, False), 10 * k),
            f"paper_example, double concave, N={N} angles",
        )
    )
    for kind in FollowerKind:
        d = design.with_kind(kind)
        rows.append(
            _row(f"analyze {kind.value}", _time(lambda d=d: analyze(d, False), 5 * k), "verify off")
        )
    rows.append(
        _row(
            "compare: 4 followers",
            _time(lambda: compare(design), 3 * k),
            "analysis.compare, verify off",
        )
    )
    rows.append(
        _row(
            "geometric check (max_lift_error)",
            _time(lambda: max_lift_error(a), 5 * k),
            f"pruned, N={N} x M={M} vertices",
        )
    )
    faces = [(f.r, f.x_c) for f in a.geo.faces]
    rows.append(
        _row(
            "geometric check brute force",
            _time(
                lambda: follower_lift(a.profile.points, a.theta, faces, a.geo.r_b, prune=False),
                2 * k,
            ),
            "follower_lift(prune=False), the O(N M) reference",
        )
    )
    rows.append(
        _row(
            "analyze with verify",
            _time(lambda: analyze(design, True), 3 * k),
            "analysis + geometric check",
        )
    )
    rows.append(
        _row("STL export", _time(lambda: stl_bytes(a), 5 * k), f"{M} profile vertices, binary STL")
    )
    rows.append(_row("DXF export", _time(lambda: dxf_bytes(a), 5 * k), "R2010 LWPOLYLINE"))
    for res in (0.5, 0.1, 0.01):
        d = _with_resolution(design, res)
        n = max(2, int((3 if res >= 0.1 else 1) * k))
        rows.append(
            _row(
                f"analyze at {res:g} deg",
                _time(lambda d=d: analyze(d, False), n),
                f"N={analyze(d, False).theta.size} angles, verify off",
            )
        )
    if not quick:
        d = _with_resolution(design, 0.01)
        rows.append(
            _row(
                "analyze+verify at 0.01 deg",
                _time(lambda: analyze(d, True), 1, warmup=0),
                "36000 angles x ~47000 vertices",
            )
        )
    for n in (1, 10, 100):
        designs = _batch(n)
        reps = 2 if (quick or n == 100) else 3 * k
        ms = _time(lambda ds=designs: [analyze(x, False) for x in ds], reps)
        rows.append(
            _row(
                f"batch of {n} designs",
                ms,
                f"loop of analyze(verify=False); {np.median(ms) / n:.2f} ms/design",
            )
        )
    rows += _pareto_rows(quick)
    return rows


def _pareto_rows(quick: bool) -> list[dict]:
    """The Pareto front of n random designs x 2 and 3 figures (camcore.sweep.pareto_mask),
    with its floor in the same run: one lexicographic sort of the same rows (np.unique,
    which any front search needs first)."""
    from camcore.sweep import pareto_mask

    n = 100_000 if quick else 1_000_000
    rng = np.random.default_rng(0)
    out = []
    for k in (2, 3):
        v = rng.random((n, k))
        floor = float(np.median(_time(lambda v=v: np.unique(v, axis=0), 3, warmup=0)))
        ms = _time(lambda v=v: pareto_mask(v), 3, warmup=0)
        front, ratio = int(pareto_mask(v).sum()), np.median(ms) / floor
        out.append(
            _row(
                f"Pareto front, {n:,} designs x {k} figures",
                ms,
                f"{front} on it; {ratio:.1f}x one sort of the rows ({floor:.0f} ms)",
            )
        )
    return out


if __name__ == "__main__":
    for r in run(quick=True):
        print(r)
