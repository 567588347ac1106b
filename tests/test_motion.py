"""Motion laws against published peak factors and against their own calculus."""

import math

import numpy as np
import pytest

from camcore.model import Design, Motion, MotionLaw
from camcore.motion import (
    FALL,
    HIGH,
    LOW,
    MIN_MOTION_STEPS,
    RISE,
    peak_factors,
    program,
    rise,
    segment_of,
    theta_grid,
)

# (C_v, C_a, C_j) from Norton, Cam Design and Manufacturing Handbook (2nd ed.), Table 3-2,
# and Chen, Mechanics and Design of Cam Mechanisms; None where the jerk is unbounded/not listed.
LITERATURE = {
    MotionLaw.cycloidal: (2.0, 6.2832, 39.478),
    MotionLaw.simple_harmonic: (1.5708, 4.9348, None),
    MotionLaw.poly_345: (1.875, 5.7735, 60.0),
    MotionLaw.poly_4567: (2.1875, 7.5132, 52.5),
    MotionLaw.modified_trapezoid: (2.0, 4.888, 61.43),
    MotionLaw.modified_sine: (1.76, 5.528, 69.47),
    MotionLaw.constant_velocity: (1.0, 0.0, 0.0),  # s = x
    MotionLaw.polynomial: (1.875, 5.7735, 60.0),  # rest to rest it is the 3-4-5
}
REST_TO_REST = [law for law in MotionLaw if law is not MotionLaw.constant_velocity]


@pytest.mark.parametrize("law", list(MotionLaw))
def test_peak_factors_match_literature(law):
    cv, ca, cj = peak_factors(law)
    ref_v, ref_a, ref_j = LITERATURE[law]
    assert cv == pytest.approx(ref_v, rel=2e-3)
    assert ca == pytest.approx(ref_a, rel=2e-3, abs=1e-12)
    if ref_j is not None:
        assert cj == pytest.approx(ref_j, rel=2e-3, abs=1e-12)


@pytest.mark.parametrize("law", REST_TO_REST)
def test_end_conditions(law):
    r = rise(law, np.array([0.0, 1.0]))
    np.testing.assert_allclose(r.s, [0.0, 1.0], atol=1e-12)
    np.testing.assert_allclose(r.v, [0.0, 0.0], atol=1e-12)
    if law is not MotionLaw.simple_harmonic:  # SHM has finite end accelerations
        np.testing.assert_allclose(r.a, [0.0, 0.0], atol=1e-9)


@pytest.mark.parametrize("law", list(MotionLaw))
def test_derivatives_are_consistent(law):
    """v, a, j are the derivatives of s, v, a (central differences, away from kinks)."""
    x = np.linspace(0.0, 1.0, 8001)
    r = rise(law, x)
    dx = x[1] - x[0]
    for f, df in ((r.s, r.v), (r.v, r.a), (r.a, r.j)):
        num = (f[2:] - f[:-2]) / (2 * dx)
        scale = np.max(np.abs(df)) + 1.0
        # the piecewise laws change formula at multiples of 1/8: skip those points
        xm = x[1:-1]
        ok = np.abs(xm * 8 - np.round(xm * 8)) > 3 * dx * 8
        assert np.max(np.abs(num - df[1:-1])[ok]) < 1e-4 * scale


@pytest.mark.parametrize("law", list(MotionLaw))
def test_monotone_rise(law):
    r = rise(law, np.linspace(0, 1, 2001))
    assert np.all(np.diff(r.s) >= -1e-15)


def test_program_pieces_and_scaling():
    d = Design(motion=Motion(lift_mm=15, rise_deg=100, high_dwell_deg=70, fall_deg=130))
    th = theta_grid(d)
    p = program(d, th)
    h, br, bf = 0.015, math.radians(100), math.radians(130)
    assert p.S.max() == pytest.approx(h)
    assert np.all(p.S[p.segment == HIGH] == h)
    assert np.all(p.S[p.segment == LOW] == 0)
    # cycloidal: V_max = 2h/beta (rise), -2h/beta (fall); A_max = 2 pi h / beta^2
    assert p.V.max() == pytest.approx(2 * h / br, rel=1e-6)
    assert p.V.min() == pytest.approx(-2 * h / bf, rel=1e-6)
    assert np.abs(p.A[th < br]).max() == pytest.approx(2 * math.pi * h / br**2, rel=1e-5)
    # the grid hits every boundary and spans one turn
    for b in (0, 100, 170, 300):
        assert np.min(np.abs(np.degrees(th) - b)) < 1e-9
    assert th[-1] < 2 * math.pi and np.all(np.diff(th) > 0)


def test_grid_resolution():
    d = Design()
    assert theta_grid(d).size == 3600
    coarse = d.model_copy(update={"limits": d.limits.model_copy(update={"resolution_deg": 1.0})})
    th = np.degrees(theta_grid(coarse))
    # no step is longer than the resolution; each rise/fall has MIN_MOTION_STEPS at least
    assert np.diff(np.append(th, 360.0)).max() <= 1.0 + 1e-9
    assert np.sum(th < 100) == MIN_MOTION_STEPS == 120  # 100 deg rise: 120 > 100 steps
    assert np.sum((th >= 170) & (th < 300)) == 130  # 130 deg fall at 1 deg
    assert th.size == 120 + 70 + 130 + 60


def test_segment_shorter_than_the_grid_is_resolved():
    """Issue 8: a 0.9 deg rise at 1 deg resolution was one sample; now it has 120."""
    d = Design.model_validate(
        {"motion": {"lift_mm": 8, "rise_deg": 0.9}, "limits": {"resolution_deg": 1.0}}
    )
    th = np.degrees(theta_grid(d))
    rise = th[th < 0.9]
    assert rise.size == MIN_MOTION_STEPS
    assert np.diff(rise).max() == pytest.approx(0.9 / MIN_MOTION_STEPS)
    p = program(d, np.radians(rise))
    assert np.all(p.segment == RISE) and p.V.max() > 0


def test_boundaries_belong_to_the_motion_segments():
    d = Design(motion=Motion(rise_deg=100, high_dwell_deg=70, fall_deg=130))
    seg = segment_of(d, np.radians([0.0, 100.0, 100.5, 170.0, 300.0, 300.5]))
    assert seg.tolist() == [RISE, RISE, HIGH, FALL, FALL, LOW]
    no_dwell = Design(motion=Motion(rise_deg=180, high_dwell_deg=0, fall_deg=180))
    assert segment_of(no_dwell, np.radians([180.0, 180.1])).tolist() == [RISE, FALL]
