"""The benchmark floor (bench/floor.py) computes the same numbers as camcore: a floor
that skipped work would make every ratio look better than it is."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "bench"))

from floor import constants, floor  # noqa: E402

from camcore.analysis import analyze  # noqa: E402
from camcore.model import load_preset  # noqa: E402


def test_floor_equals_the_analysis_on_the_paper_example():
    d = load_preset("paper_example")
    a = analyze(d, verify=False)
    f = floor(a.theta, constants(d))
    np.testing.assert_allclose(f["S"], a.prog.S, atol=1e-15)
    np.testing.assert_allclose(f["V"], a.prog.V, atol=1e-14)
    np.testing.assert_allclose(f["A"], a.prog.A, atol=1e-12)
    for i in range(len(a.geo.faces)):
        np.testing.assert_allclose(f["phi"][i], a.pressure_angle[i], atol=1e-12)
        np.testing.assert_allclose(f["rho"][i], a.rho[i], rtol=1e-9)
        np.testing.assert_allclose(np.stack(f["body"][i], -1), a.point_body[i], atol=1e-12)


def test_the_ratio_bench_reports_every_goal_beside_its_figure():
    """Issue 12's first 'done when': the bench reports each ratio beside its goal. Its
    quick run (~3 s) has a row per goal, each note naming the goal, and the rows that
    time the check for the other followers and split the batched sweep's time."""
    import bench_ratios

    rows = {r["name"]: r for r in bench_ratios.run(quick=True)}
    goals = [
        "analyze(verify=False)",
        "geometric check",
        "geometric check at 0.02 deg",
        "geometric check, single_roller",
        "geometric check, double_roller",
        "geometric check, single_concave",
        "sweep (verify off), per design",
        "sweep --fast (batched core), per design",
    ]
    for name in goals:
        assert "goal" in rows[name]["note"] and rows[name]["median_ms"] > 0, name
    split = rows["sweep --fast: all but the closed forms, per design"]
    fast = rows["sweep --fast (batched core), per design"]
    assert 0 < split["median_ms"] < fast["median_ms"]
    assert "four separate analyses" in rows["compare: 4 followers, one grid"]["note"]
