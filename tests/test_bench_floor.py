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
