"""Motion laws and the follower displacement program S(theta).

A rise law is a normalized function s(x) on x in [0, 1] with s(0) = 0, s(1) = 1
and zero velocity at both ends. Two families cover the six laws:

* polynomials (3-4-5, 4-5-6-7), evaluated with exact derivatives;
* piecewise sinusoid-plus-constant accelerations (cycloidal, simple harmonic,
  modified trapezoid, modified sine), integrated in closed form segment by
  segment and scaled so that s(1) = 1.

Peak factors (C_v, C_a, C_j in s' = C_v, s'' = C_a, s''' = C_j) match the
literature (Norton, *Cam Design and Manufacturing Handbook*, 2nd ed., Table 3-2;
Chen, *Mechanics and Design of Cam Mechanisms*); tests/test_motion.py checks them.

The program S(theta) is piecewise: rise over [0, beta_r], high dwell, fall over
[beta_r + beta_h, beta_r + beta_h + beta_f], low dwell to 360 deg. Derivatives are
per radian of cam angle (the paper's V(theta) and A(theta)); multiply by
omega, omega^2, omega^3 for time derivatives.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache

import numpy as np

from .model import DEG, MM, Design, MotionLaw


@dataclass(frozen=True)
class Normalized:
    """s(x) and its first three derivatives with respect to x."""

    s: np.ndarray
    v: np.ndarray
    a: np.ndarray
    j: np.ndarray


# --- polynomial laws -------------------------------------------------------------------

_POLY = {
    # s = sum c_k x^k
    MotionLaw.poly_345: {3: 10.0, 4: -15.0, 5: 6.0},
    MotionLaw.poly_4567: {4: 35.0, 5: -84.0, 6: 70.0, 7: -20.0},
}


def _poly(coeffs: dict[int, float], x: np.ndarray) -> Normalized:
    out = [np.zeros_like(x) for _ in range(4)]
    for k, c in coeffs.items():
        for d in range(4):
            if k - d >= 0:
                out[d] += c * math.perm(k, d) * x ** (k - d)
    return Normalized(*out)


# --- piecewise sinusoidal-acceleration laws -------------------------------------------
# Each segment on [x0, x1]: a(u) = c0 + cc*cos(w*u) + cs*sin(w*u), u = x - x0.

_QUARTER = 4.0 * math.pi  # a quarter sine wave over 1/8 of the interval


def _segments(law: MotionLaw) -> list[tuple[float, float, float, float, float, float]]:
    """(x0, x1, c0, cc, cs, w) with unit amplitude; the scale is fixed by s(1) = 1."""
    if law is MotionLaw.cycloidal:
        return [(0.0, 1.0, 0.0, 0.0, 1.0, 2 * math.pi)]
    if law is MotionLaw.simple_harmonic:
        return [(0.0, 1.0, 0.0, 1.0, 0.0, math.pi)]
    if law is MotionLaw.modified_trapezoid:
        q = _QUARTER
        return [
            (0.0, 0.125, 0.0, 0.0, 1.0, q),  # ramp up
            (0.125, 0.375, 1.0, 0.0, 0.0, 0.0),  # constant
            (0.375, 0.625, 0.0, 1.0, 0.0, q),  # half cosine through zero
            (0.625, 0.875, -1.0, 0.0, 0.0, 0.0),  # constant negative
            (0.875, 1.0, 0.0, -1.0, 0.0, q),  # ramp back to zero
        ]
    if law is MotionLaw.modified_sine:
        q, m = _QUARTER, 4.0 * math.pi / 3.0
        return [
            (0.0, 0.125, 0.0, 0.0, 1.0, q),
            (0.125, 0.875, 0.0, 1.0, 0.0, m),  # 3/4 of a period-3/2 cosine
            (0.875, 1.0, 0.0, -1.0, 0.0, q),
        ]
    raise KeyError(law)


def _seg_eval(u, c0, cc, cs, w):
    """Acceleration, jerk, and the increments of v and s over u for one segment."""
    if w == 0.0:
        return c0 + 0 * u, 0 * u, c0 * u, c0 * u**2 / 2
    cos, sin = np.cos(w * u), np.sin(w * u)
    a = c0 + cc * cos + cs * sin
    j = w * (cs * cos - cc * sin)
    dv = c0 * u + cc * sin / w + cs * (1 - cos) / w
    ds = c0 * u**2 / 2 + cc * (1 - cos) / w**2 + cs * (u / w - sin / w**2)
    return a, j, dv, ds


@cache
def _segment_table(law: MotionLaw):
    """Start values (v0, s0) of every segment and the amplitude making s(1) = 1."""
    segs = _segments(law)
    v0, s0, table = 0.0, 0.0, []
    for x0, x1, c0, cc, cs, w in segs:
        table.append((x0, x1, c0, cc, cs, w, v0, s0))
        u = np.array(x1 - x0)
        _, _, dv, ds = _seg_eval(u, c0, cc, cs, w)
        s0, v0 = s0 + v0 * (x1 - x0) + float(ds), v0 + float(dv)
    return tuple(table), 1.0 / s0


def _sinusoid(law: MotionLaw, x: np.ndarray) -> Normalized:
    table, scale = _segment_table(law)
    s, v, a, j = (np.zeros_like(x) for _ in range(4))
    for x0, x1, c0, cc, cs, w, v0, s0 in table:
        m = (x >= x0) & (x <= x1)
        u = x[m] - x0
        aa, jj, dv, ds = _seg_eval(u, c0, cc, cs, w)
        a[m], j[m], v[m], s[m] = aa, jj, v0 + dv, s0 + v0 * u + ds
    return Normalized(s * scale, v * scale, a * scale, j * scale)


def rise(law: MotionLaw, x: np.ndarray) -> Normalized:
    """Normalized rise s(x), x in [0, 1] (values outside are clipped)."""
    x = np.clip(np.asarray(x, dtype=float), 0.0, 1.0)
    law = MotionLaw(law)
    return _poly(_POLY[law], x) if law in _POLY else _sinusoid(law, x)


def peak_factors(law: MotionLaw, n: int = 20001) -> tuple[float, float, float]:
    """(C_v, C_a, C_j): max |s'|, |s''|, |s'''| over [0, 1]."""
    r = rise(law, np.linspace(0.0, 1.0, n))
    return float(np.max(np.abs(r.v))), float(np.max(np.abs(r.a))), float(np.max(np.abs(r.j)))


# --- the whole program -----------------------------------------------------------------

RISE, HIGH, FALL, LOW = 0, 1, 2, 3  # segment codes: rise, high dwell, fall, low dwell
MOTIONS = (RISE, FALL)
# Every rise or fall gets at least this many analysis steps, whatever the resolution:
# a segment shorter than the grid step is otherwise judged on one sample (issue 8).
MIN_MOTION_STEPS = 120
MIN_DWELL_STEPS = 4


@dataclass(frozen=True)
class Segment:
    """One piece of the motion program: [start, end] cam angles [rad], the displacement
    S0 at its start and S1 at its end [m], and the law of a rise or fall."""

    code: int  # RISE, HIGH, FALL or LOW
    start: float
    end: float
    S0: float
    S1: float
    law: MotionLaw | None = None

    @property
    def is_motion(self) -> bool:
        return self.code in MOTIONS

    @property
    def length(self) -> float:
        return self.end - self.start


def segments(design: Design) -> tuple[Segment, ...]:
    """The program as segments covering [0, 2 pi).

    A zero-length high dwell is left out. A zero-length low dwell is kept (as an empty
    segment at 2 pi): between a fall and a rise the cam still carries a dwell arc of
    2 psi_l (Eq. 26 with beta_l = 0) on which the two faces of a double follower meet,
    and the profile must include it."""
    m = design.motion
    h = m.lift_mm * MM
    t1, t2, t3, t4 = boundaries_rad(design)
    parts = (
        Segment(RISE, 0.0, t1, 0.0, h, m.rise_law),
        Segment(HIGH, t1, t2, h, h),
        Segment(FALL, t2, t3, h, 0.0, m.fall_law),
        Segment(LOW, t3, t4, 0.0, 0.0),
    )
    return tuple(p for p in parts if p.is_motion or p.length > 1e-12 or p.code == LOW)


@dataclass(frozen=True)
class Program:
    """S(theta) [m] and its derivatives per radian of cam angle, with segment labels."""

    theta: np.ndarray  # cam angle [rad], 0 .. 2 pi
    S: np.ndarray  # displacement [m]
    V: np.ndarray  # dS/dtheta [m/rad]
    A: np.ndarray  # d2S/dtheta2 [m/rad^2]
    J: np.ndarray  # d3S/dtheta3 [m/rad^3]
    segment: np.ndarray  # segment code: 0 rise, 1 high dwell, 2 fall, 3 low dwell
    index: np.ndarray  # index into segments(design) of each angle


def boundaries_rad(design: Design) -> tuple[float, float, float, float]:
    """Cam angles [rad] where rise ends, high dwell ends, fall ends, and 2 pi."""
    m = design.motion
    t1 = m.rise_deg * DEG
    t2 = t1 + m.high_dwell_deg * DEG
    t3 = t2 + m.fall_deg * DEG
    return t1, t2, t3, 2 * math.pi


def segment_index(segs: tuple[Segment, ...], theta: np.ndarray) -> np.ndarray:
    """Index of the segment holding each cam angle [rad, in 0 .. 2 pi).

    A boundary between two segments belongs to the motion (rise or fall) segment, so
    the ends of a rise or fall are evaluated with its law; between two motions it
    belongs to the earlier one.
    """
    ends = np.array([g.end for g in segs])
    idx = np.minimum(np.searchsorted(ends, theta, side="left"), len(segs) - 1)
    nxt = np.minimum(idx + 1, len(segs) - 1)
    motion = np.array([g.is_motion for g in segs])
    at_end = theta >= ends[idx]
    return np.where(at_end & ~motion[idx] & motion[nxt] & (nxt > idx), nxt, idx)


def segment_of(design: Design, theta: np.ndarray) -> np.ndarray:
    """Segment code (RISE, HIGH, FALL, LOW) of each cam angle [rad]."""
    segs = segments(design)
    codes = np.array([g.code for g in segs], dtype=np.int8)
    return codes[segment_index(segs, np.mod(np.asarray(theta, dtype=float), 2 * math.pi))]


def program(design: Design, theta: np.ndarray) -> Program:
    """Evaluate S, V, A, J at the cam angles ``theta`` [rad] (vectorized).

    A rise or fall of lift H over beta is S = S0 + H s(x), x = (theta - start)/beta,
    so V = H s'/beta, A = H s''/beta^2, J = H s'''/beta^3 (H < 0 for a fall).
    """
    segs = segments(design)
    th = np.mod(np.asarray(theta, dtype=float), 2 * math.pi)
    idx = segment_index(segs, th)
    S, V, A, J = (np.zeros_like(th) for _ in range(4))
    for i, g in enumerate(segs):
        m = idx == i
        if not g.is_motion:
            S[m] = g.S0
            continue
        H, beta = g.S1 - g.S0, g.length
        n = rise(g.law, (th[m] - g.start) / beta)
        S[m] = g.S0 + H * n.s
        V[m], A[m], J[m] = H * n.v / beta, H * n.a / beta**2, H * n.j / beta**3
    codes = np.array([g.code for g in segs], dtype=np.int8)
    return Program(th, S, V, A, J, codes[idx], idx)


def theta_grid(design: Design, extra: tuple[float, ...] = ()) -> np.ndarray:
    """Cam angles [rad] from 0 to just below 2 pi (the cycle closes on itself).

    Every segment boundary and every angle in ``extra`` (e.g. the stations) is on the
    grid exactly. Each piece between them gets ceil(length / resolution) steps, and a
    rise or fall at least MIN_MOTION_STEPS (a dwell MIN_DWELL_STEPS) however coarse the
    resolution, so that no segment is judged on a single sample.
    """
    res = design.limits.resolution_deg * DEG
    parts = []
    for g in segments(design):
        cuts = sorted({g.start, g.end, *(t for t in extra if g.start < t < g.end)})
        need = MIN_MOTION_STEPS if g.is_motion else MIN_DWELL_STEPS
        for a, b in zip(cuts[:-1], cuts[1:], strict=True):
            if b - a <= 1e-12:
                continue
            share = max(1, math.ceil(need * (b - a) / g.length - 1e-9))
            n = max(share, math.ceil((b - a) / res - 1e-9))
            parts.append(np.linspace(a, b, n, endpoint=False))
    return np.concatenate(parts)
