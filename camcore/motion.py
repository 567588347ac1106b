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
from collections.abc import Sequence
from dataclasses import dataclass, replace
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
    """Normalized rise s(x), x in [0, 1] (values outside are clipped).

    ``constant_velocity`` is s = x. ``polynomial`` has no normalized form (it is fitted
    to its neighbours, see ``fit_quintic``); here it is the rest-to-rest quintic 3-4-5."""
    x = np.clip(np.asarray(x, dtype=float), 0.0, 1.0)
    law = MotionLaw(law)
    if law is MotionLaw.constant_velocity:
        return Normalized(x.copy(), np.ones_like(x), np.zeros_like(x), np.zeros_like(x))
    if law is MotionLaw.polynomial:
        law = MotionLaw.poly_345
    return _poly(_POLY[law], x) if law in _POLY else _sinusoid(law, x)


def fit_quintic(
    S0: float, V0: float, A0: float, S1: float, V1: float, A1: float, beta: float
) -> tuple[float, ...]:
    """Coefficients c_0..c_5 of S(x) = sum c_k x^k, x = (theta - start) / beta in [0, 1],
    with S, dS/dtheta, d2S/dtheta2 given at both ends (SI: m, m/rad, m/rad^2).

    The general degree-5 polynomial of the cam literature (Norton, Cam Design and
    Manufacturing Handbook, ch. 4; VDI 2143's 'Polynom 5. Grades'): with x-derivatives
    v = V beta, a = A beta^2 the first three coefficients are the start values and the
    last three solve a 3x3 system for the end values."""
    v0, a0, v1, a1 = V0 * beta, A0 * beta**2, V1 * beta, A1 * beta**2
    c0, c1, c2 = S0, v0, a0 / 2
    rhs = np.array([S1 - c0 - c1 - c2, v1 - c1 - 2 * c2, a1 - 2 * c2])
    m = np.array([[1.0, 1.0, 1.0], [3.0, 4.0, 5.0], [6.0, 12.0, 20.0]])
    c3, c4, c5 = np.linalg.solve(m, rhs)
    return (c0, c1, c2, float(c3), float(c4), float(c5))


def peak_factors(law: MotionLaw, n: int = 20001) -> tuple[float, float, float]:
    """(C_v, C_a, C_j): max |s'|, |s''|, |s'''| over [0, 1]."""
    r = rise(law, np.linspace(0.0, 1.0, n))
    return float(np.max(np.abs(r.v))), float(np.max(np.abs(r.a))), float(np.max(np.abs(r.j)))


# --- the whole program -----------------------------------------------------------------

RISE, HIGH, FALL, LOW = 0, 1, 2, 3  # segment codes: rise, high dwell, fall, low dwell
MOTIONS = (RISE, FALL)
SEGMENT_NAMES = {RISE: "rise", HIGH: "high dwell", FALL: "fall", LOW: "low dwell"}

# Every rise or fall gets at least this many analysis steps, whatever the resolution:
# a segment shorter than the grid step is otherwise judged on one sample (issue 8).
MIN_MOTION_STEPS = 120
MIN_DWELL_STEPS = 4


@dataclass(frozen=True)
class Segment:
    """One piece of the motion program: [start, end] cam angles [rad], the displacement
    S0 at its start and S1 at its end [m], the law of a rise or fall, and for a
    ``polynomial`` law its coefficients in x = (theta - start) / length (fit_quintic)."""

    code: int  # RISE, HIGH, FALL or LOW (a dwell at S = 0 is LOW, any other HIGH)
    start: float
    end: float
    S0: float
    S1: float
    law: MotionLaw | None = None
    coeffs: tuple[float, ...] | None = None
    row: int | None = None  # the program's segment it is (0-based); None: a dwell added

    @property
    def is_motion(self) -> bool:
        return self.code in MOTIONS

    @property
    def length(self) -> float:
        return self.end - self.start

    def ends(self) -> tuple[float, float, float, float]:
        """(V, A) at the start and (V, A) at the end [m/rad, m/rad^2], from the closed
        forms (not sampled): what the continuity check compares across boundaries."""
        if not self.is_motion:
            return 0.0, 0.0, 0.0, 0.0
        beta = self.length
        if self.coeffs is not None:
            c = self.coeffs
            return (
                c[1] / beta,
                2 * c[2] / beta**2,
                (c[1] + 2 * c[2] + 3 * c[3] + 4 * c[4] + 5 * c[5]) / beta,
                (2 * c[2] + 6 * c[3] + 12 * c[4] + 20 * c[5]) / beta**2,
            )
        H = self.S1 - self.S0
        assert self.law is not None  # a motion segment without coefficients has a law
        n = rise(self.law, np.array([0.0, 1.0]))
        return (H * n.v[0] / beta, H * n.a[0] / beta**2, H * n.v[1] / beta, H * n.a[1] / beta**2)


REST_TOL_M = 1e-7  # [m]: a dwell this near the base circle is the low dwell, and dwells
# this near each other in displacement are one rest (profile.dwell_run): the lifts of a
# program close to 1e-9 of their sum (model.Motion), e.g. 3 x 3.33333333 mm down after
# 10 mm up leaves 1e-11 m


def segments(design: Design) -> tuple[Segment, ...]:
    """The program as segments covering [0, 2 pi), in order from theta = 0.

    Displacements are offset so that the lowest is S = 0 (the base circle). Zero-length
    dwells are left out, except between a fall and a rise: there the cam still carries
    a dwell arc of 2 psi (Eq. 26 with beta = 0) on which the two faces of a double
    follower meet, so an empty dwell segment is kept (or added) there. A ``polynomial``
    segment is fitted to the velocity and acceleration its neighbours end and start
    with (0 next to a dwell or another polynomial)."""
    spec = design.motion.segments
    S, low = 0.0, 0.0
    for m in spec:
        S += m.signed_lift_mm * MM
        low = min(low, S)
    S, t = -low, 0.0
    raw: list[Segment] = []
    for row, m in enumerate(spec):
        S1 = S + m.signed_lift_mm * MM
        t1 = t + m.angle_deg * DEG
        if m.kind.value == "dwell":
            code = LOW if abs(S) <= REST_TOL_M else HIGH
            raw.append(Segment(code, t, t1, S, S, row=row))
        else:
            code = RISE if m.kind.value == "rise" else FALL
            raw.append(Segment(code, t, t1, S, S1, m.law, row=row))
        S, t = S1, t1
    # the angles sum to 360 deg to round-off (1e-6 deg): no segment runs past 2 pi
    two_pi = 2 * math.pi
    raw = [replace(g, start=min(g.start, two_pi), end=min(g.end, two_pi)) for g in raw]
    raw[-1] = replace(raw[-1], end=two_pi)
    kept: list[Segment] = []
    for i, g in enumerate(raw):
        before, after = raw[i - 1], raw[(i + 1) % len(raw)]
        if g.is_motion or g.length > 1e-12:
            kept.append(g)
        elif before.code == FALL and after.code == RISE:
            kept.append(g)  # the empty dwell of a fall into a rise: it has an arc
    given = list(kept)  # (read the neighbours here: kept grows below)
    for i, g in enumerate(given):  # a fall straight into a rise: add the empty dwell
        after = given[(i + 1) % len(given)]
        if g.code == FALL and after.code == RISE:
            code = LOW if abs(g.S1) <= REST_TOL_M else HIGH
            kept.insert(kept.index(g) + 1, Segment(code, g.end, g.end, g.S1, g.S1))
    return _fit_polynomials(tuple(kept))


def _fit_polynomials(segs: tuple[Segment, ...]) -> tuple[Segment, ...]:
    out = list(segs)
    for i, g in enumerate(segs):
        if g.law is not MotionLaw.polynomial:
            continue
        before, after = segs[i - 1], segs[(i + 1) % len(segs)]
        poly = MotionLaw.polynomial
        V0, A0 = before.ends()[2:] if before.law is not poly else (0.0, 0.0)
        V1, A1 = after.ends()[:2] if after.law is not poly else (0.0, 0.0)
        out[i] = replace(g, coeffs=fit_quintic(g.S0, V0, A0, g.S1, V1, A1, g.length))
    return tuple(out)


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


def per_second(prog: Program, omega: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Follower velocity [m/s], acceleration [m/s^2] and jerk [m/s^3] at a constant cam
    speed omega [rad/s]: d/dt = omega d/dtheta, so V w, A w^2, J w^3."""
    return prog.V * omega, prog.A * omega**2, prog.J * omega**3


def boundaries_rad(design: Design) -> tuple[float, float, float, float]:
    """Cam angles [rad] where rise ends, high dwell ends, fall ends, and 2 pi (the
    paper's program; see Motion.classic)."""
    m = design.motion
    t1 = m.rise_deg * DEG
    t2 = t1 + m.high_dwell_deg * DEG
    t3 = t2 + m.fall_deg * DEG
    return t1, t2, t3, 2 * math.pi


def segment_word(segs: Sequence[Segment], i: int) -> str:
    """Segment i in words: "rise", "fall", "low dwell" (at S = 0), "high dwell" (at the
    program's largest lift, the paper's) or, for a dwell between them, "dwell at S =
    8 mm" (the middle dwell of a program rising in two steps is not high)."""
    g = segs[i]
    if g.code == HIGH and g.S0 < max(s.S1 for s in segs) - REST_TOL_M:
        s_mm = f"{g.S0 * 1e3:.3f}".rstrip("0").rstrip(".")  # (as the app's S, to 1 um)
        return f"dwell at S = {s_mm} mm"
    return SEGMENT_NAMES[g.code]


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
    idx = np.where(at_end & ~motion[idx] & motion[nxt] & (nxt > idx), nxt, idx)
    if motion[-1] and not motion[0]:  # theta = 0 is 2 pi: the end of the last motion
        idx = np.where(theta <= 0.0, len(segs) - 1, idx)
    return idx


def segment_of(design: Design, theta: np.ndarray) -> np.ndarray:
    """Segment code (RISE, HIGH, FALL, LOW) of each cam angle [rad]."""
    segs = segments(design)
    codes = np.array([g.code for g in segs], dtype=np.int8)
    return codes[segment_index(segs, np.mod(np.asarray(theta, dtype=float), 2 * math.pi))]


def program(design: Design, theta: np.ndarray, segs: tuple[Segment, ...] | None = None) -> Program:
    """Evaluate S, V, A, J at the cam angles ``theta`` [rad] (vectorized); ``segs`` are
    the design's segments if the caller has them at hand (they are the same each time).

    A rise or fall of lift H over beta is S = S0 + H s(x), x = (theta - start)/beta,
    so V = H s'/beta, A = H s''/beta^2, J = H s'''/beta^3 (H < 0 for a fall).
    """
    segs = segments(design) if segs is None else segs
    th = np.mod(np.asarray(theta, dtype=float), 2 * math.pi)
    idx = segment_index(segs, th)
    last = (idx == len(segs) - 1) & (th < segs[-1].start)  # theta = 0 as 2 pi
    at = np.where(last, th + 2 * math.pi, th)  # theta as its segment sees it
    S, V, A, J = (np.zeros_like(th) for _ in range(4))
    for i, g in enumerate(segs):
        m = idx == i
        if not g.is_motion:
            S[m] = g.S0
            continue
        if g.coeffs is not None:
            S[m], V[m], A[m], J[m] = _polynomial(g, at[m])
            continue
        H, beta = g.S1 - g.S0, g.length
        assert g.law is not None  # a motion segment without coefficients has a law
        n = rise(g.law, (at[m] - g.start) / beta)
        S[m] = g.S0 + H * n.s
        V[m], A[m], J[m] = H * n.v / beta, H * n.a / beta**2, H * n.j / beta**3
    codes = np.array([g.code for g in segs], dtype=np.int8)
    return Program(th, S, V, A, J, codes[idx], idx)


def _polynomial(g: Segment, theta: np.ndarray):
    """S, V, A, J of a fitted polynomial segment at the cam angles ``theta``."""
    beta = g.length
    x = np.clip((theta - g.start) / beta, 0.0, 1.0)
    assert g.coeffs is not None
    S, V, A, J = (np.zeros_like(x) for _ in range(4))
    for k, ck in enumerate(g.coeffs):  # c_k x^k and its derivatives in x
        S += ck * x**k
        V += k * ck * x ** max(k - 1, 0)
        A += k * (k - 1) * ck * x ** max(k - 2, 0)
        J += k * (k - 1) * (k - 2) * ck * x ** max(k - 3, 0)
    return S, V / beta, A / beta**2, J / beta**3


def continuity_jumps(segs: tuple[Segment, ...]) -> list[tuple[float, str, float]]:
    """Jumps of V or A where one segment meets the next: (cam angle [rad], "V" or "A",
    the jump [m/rad or m/rad^2]). A jump in V means an infinite acceleration, a jump
    in A an infinite jerk (the fundamental law of cam design: S, V, A continuous)."""
    out = []
    moving = [g for g in segs if g.is_motion]  # the program's own scales H/beta, H/beta^2
    scale_v = max(abs(g.S1 - g.S0) / g.length for g in moving)
    scale_a = max(abs(g.S1 - g.S0) / g.length**2 for g in moving)
    for i, g in enumerate(segs):
        nxt = segs[(i + 1) % len(segs)]
        _, _, v1, a1 = g.ends()
        v0, a0, _, _ = nxt.ends()
        at = g.end % (2 * math.pi)
        if abs(v1 - v0) > 1e-9 * scale_v:
            out.append((at, "V", v0 - v1))
        if abs(a1 - a0) > 1e-9 * scale_a:
            out.append((at, "A", a0 - a1))
    return out


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
