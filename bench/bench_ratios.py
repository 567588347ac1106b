"""Issue 12's goals as ratios to a floor measured in the same run (bench/floor.py), so
a shared, noisy machine still gives comparable numbers.

Rows (median ms, and the ratio with its goal in the note):
* floor: the closed forms of the paper example on its grid;
* analyze(verify=False) / floor (goal <= 3);
* geometric check / analysis (goal <= 3) and its growth exponent from 0.1 to 0.02 deg
  (goal: 1, i.e. O(N)); the same ratio for the paper's three other followers;
* the four-follower comparison (one grid, one motion program) against four separate
  analyses;
* a sweep's designs per CPU-second against the floor's rate (goal >= 0.5): one full
  analysis per design, and the batched core (``camcore sweep --fast``, camcore.batch)
  on chunks of 64 designs (32 quick), and what of the batched core's time is not the closed
  forms at its angles (``batch.local``): what a fused kernel of them would leave.
"""

from __future__ import annotations

import json
import math
import time

import numpy as np
from floor import constants, floor
from rows import row as _row

from camcore.analysis import analyze
from camcore.model import Design, load_preset
from camcore.verify import max_lift_error


def _median_ms(fn, n: int) -> float:
    fn()
    out = []
    for _ in range(n):
        t0 = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t0)
    return float(np.median(out)) * 1e3


def _cpu_ms(fn) -> float:
    t0 = time.process_time()
    fn()
    return (time.process_time() - t0) * 1e3


def _res(design: Design, res: float) -> Design:
    data = design.model_dump()
    data["limits"]["resolution_deg"] = res
    return Design.model_validate(data)


def run(quick: bool = False) -> list[dict]:
    n = 5 if quick else 20
    d = load_preset("paper_example")
    a = analyze(d, verify=False)
    c = constants(d)
    t_floor = _median_ms(lambda: floor(a.theta, c), 4 * n)
    t_an = _median_ms(lambda: analyze(d, verify=False), n)
    t_check = _median_ms(lambda: max_lift_error(a), n)
    rows = [
        _row("floor (closed forms, numpy)", t_floor, f"N = {a.theta.size} angles, 2 faces"),
        _row("analyze(verify=False)", t_an, f"ratio to floor {t_an / t_floor:.1f}x (goal <= 3x)"),
        _row(
            "geometric check", t_check, f"ratio to the analysis {t_check / t_an:.2f}x (goal <= 3x)"
        ),
    ]
    times = {}
    for res in (0.1, 0.02):
        ar = analyze(_res(d, res), verify=False)
        times[res] = (ar.theta.size, _median_ms(lambda ar=ar: max_lift_error(ar), max(2, n // 4)))
    (n1, t1), (n2, t2) = times[0.1], times[0.02]
    slope = math.log(t2 / t1) / math.log(n2 / n1)
    rows.append(
        _row(
            "geometric check at 0.02 deg", t2, f"N {n1} -> {n2}: grows as N^{slope:.2f} (goal: N^1)"
        )
    )
    from camcore.analysis import compare

    kinds = ("single_roller", "double_roller", "single_concave", "double_concave")
    rows += [_check_row(d.with_kind(k), max(3, n // 2)) for k in kinds if k != d.follower.kind]
    t_cmp = _median_ms(lambda: compare(d), max(3, n // 2))
    t_four = _median_ms(
        lambda: [analyze(d.with_kind(k), verify=False) for k in kinds], max(3, n // 2)
    )
    rows.append(
        _row(
            "compare: 4 followers, one grid",
            t_cmp,
            f"{t_cmp / t_four:.2f}x four separate analyses ({t_four:.1f} ms)",
        )
    )
    from camcore import sweep

    num = 8 if quick else 32
    spec = sweep.parse_spec(
        json.dumps({"grid": {"cam.base_radius_mm": {"from": 70, "to": 90, "num": num}}})
    )
    points = list(spec.points())
    cpu = _cpu_ms(lambda: sweep.run_chunk(spec.base, points, verify=False))
    rate, floor_rate = len(points) / (cpu / 1e3), 1e3 / t_floor
    rows.append(
        _row(
            "sweep (verify off), per design",
            cpu / len(points),
            f"{rate:.0f} designs per CPU-second; floor {floor_rate:.0f}/s: "
            f"{rate / floor_rate:.3f} of it (goal >= 0.5)",
        )
    )
    fast_spec = sweep.parse_spec(  # 32 or 64 distinct designs (a repeated point is
        # analysed once: camcore.sweep.same_designs)
        json.dumps(
            {
                "grid": {
                    "cam.base_radius_mm": {
                        "from": 70,
                        "to": 90,
                        "num": 4 * num if quick else 2 * num,
                    }
                }
            }
        )
    )
    fast_points = list(fast_spec.points())
    sweep.run_chunk(fast_spec.base, fast_points[:8], fast=True)
    cpu, closed = min(
        _split_cpu_ms(lambda: sweep.run_chunk(fast_spec.base, fast_points, fast=True))
        for _ in range(3)
    )
    per, rest = cpu / len(fast_points), (cpu - closed) / len(fast_points)
    rate = len(fast_points) / (cpu / 1e3)
    rows.append(
        _row(
            "sweep --fast (batched core), per design",
            per,
            f"{rate:.0f} designs per CPU-second in chunks of {len(fast_points)}: "
            f"{rate / floor_rate:.3f} of the floor's rate (goal >= 0.5)",
        )
    )
    rows.append(
        _row(
            "sweep --fast: all but the closed forms, per design",
            rest,
            f"{rest / t_floor:.1f}x the floor's time; with the closed forms free "
            f"(batch.local: grids and search, {per - rest:.2f} ms) the rate would be "
            f"{t_floor / rest:.2f} of the floor's",
        )
    )
    return rows


def _check_row(design: Design, n: int) -> dict:
    """The check's ratio to the analysis for another of the paper's followers (its
    profile, its faces): the goal holds for each, not for the paper's own only."""
    a = analyze(design, verify=False)
    t_an = _median_ms(lambda: analyze(design, verify=False), n)
    t_check = _median_ms(lambda: max_lift_error(a), n)
    return _row(
        f"geometric check, {design.follower.kind.value}",
        t_check,
        f"ratio to its analysis ({t_an:.1f} ms) {t_check / t_an:.2f}x (goal <= 3x)",
    )


def _split_cpu_ms(fn) -> tuple[float, float]:
    """CPU ms of fn() and of its calls of camcore.batch.local (the closed forms at
    every angle of a batch: its grids and the search between samples), the part a
    fused kernel (bench/experiments/numba_fused.py) would replace."""
    from camcore import batch

    inner = batch.local
    spent = [0.0]

    def timed(*args, **kwargs):
        t0 = time.process_time()
        try:
            return inner(*args, **kwargs)
        finally:
            spent[0] += time.process_time() - t0

    batch.local = timed
    try:
        total = _cpu_ms(fn)
    finally:
        batch.local = inner
    return total, spent[0] * 1e3


if __name__ == "__main__":
    for r in run(quick=True):
        print(r["name"], f"{r['median_ms']:.3f} ms", r["note"])
