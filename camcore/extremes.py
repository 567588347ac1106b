"""Worst values of the checked quantities between the grid samples.

A verdict must hold for the real cam, not only at the analysed angles. On a rise or
fall every checked quantity (pressure angle, pitch curvature, contact force, Hertz
stress) is a closed-form function of the cam angle, so its extremes can be found
rather than sampled: each local extreme of the grid samples brackets a true extreme
between its two neighbours, and a zoom search (vectorized over all brackets at once,
one evaluation of the closed forms per round) samples POINTS angles per bracket and
keeps the two spacings around the best: after ROUNDS rounds the bracket is 1/4096 of
its width, far below any difference that matters. Dwells need no search: there every
quantity is constant on each contact window.

The grid itself resolves every rise and fall with motion.MIN_MOTION_STEPS samples at
least, so no extreme hides in a segment shorter than the resolution.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

ROUNDS = 3  # zoom rounds: each samples POINTS per bracket in one evaluation
POINTS = 33  # a 16-fold zoom per round: 4096-fold in all (3 evaluations, not 4)
CANDIDATES = 4  # local extremes refined per quantity and face (the worst first)

# name -> (per-face quantity of a camcore.analysis.Local, +1 maximize / -1 minimize)
QUANTITIES = {
    "pressure_angle_max": (lambda loc: np.abs(loc.pressure_angle), 1.0),  # [rad]
    "kappa_pitch_max": (lambda loc: loc.kappa_pitch, 1.0),  # [1/m]
    "kappa_pitch_min": (lambda loc: loc.kappa_pitch, -1.0),
    "FN_min": (lambda loc: loc.FN, -1.0),  # [N]
    "stress_max": (lambda loc: loc.stress, 1.0),  # [Pa]
    "torque_max": (lambda loc: loc.torque, 1.0),  # [N m], driving
    "torque_min": (lambda loc: loc.torque, -1.0),  # braking
}


@dataclass(frozen=True)
class Worst:
    """The worst value of a quantity on the rise and fall curves (not only at samples)."""

    value: float  # in the quantity's SI unit
    theta: float  # cam angle where it occurs [rad]
    face: int
    others: tuple[tuple[float, float, float], ...] = ()  # (value, lo, hi) of every
    # refined local extreme, with the grid angles [rad] that bracket it

    def beyond(self, limit: float, sense: float) -> tuple[tuple[float, float], ...]:
        """Brackets [rad] of the refined extremes that pass ``limit`` (sense as above)."""
        return tuple((lo, hi) for v, lo, hi in self.others if sense * (v - limit) > 0)


def _candidates(values: np.ndarray, mask: np.ndarray) -> list[tuple[int, int]]:
    """(face, grid index) of the CANDIDATES largest local maxima of ``values`` per face,
    among the samples in ``mask`` (the face driving a rise or fall)."""
    out = []
    for i in range(values.shape[0]):
        v = np.where(mask[i], values[i], -np.inf)
        left = np.concatenate([[-np.inf], v[:-1]])
        right = np.concatenate([v[1:], [-np.inf]])
        peak = np.flatnonzero(mask[i] & (v >= left) & (v >= right) & np.isfinite(v))
        peak = peak[np.argsort(-v[peak], kind="stable")[:CANDIDATES]]
        out += [(i, int(k)) for k in peak]
    return out


def distinct_rows(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The distinct rows of ``x`` (brackets, POINTS) and, per row of x, its row among
    them: brackets of several quantities often sample the very same angles (a stress
    peak where F_N peaks), and the closed forms need evaluating there once. (The batch
    uses it; for one design's ~20 brackets the sort costs what it saves.)"""
    rows, inv = np.unique(x, axis=0, return_inverse=True)
    return rows, inv.reshape(-1)


def zoom(f, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Maximize f over every bracket [lo, hi] at once (f: angles -> values, row-major
    (bracket, point)); returns the best (value, angle) found.

    Each round samples POINTS evenly over each bracket in one evaluation and shrinks it
    to the two spacings around its best sample: a (POINTS - 1) / 2-fold zoom per round
    that also copes with kinks (a guide-mode switch) and two maxima in one bracket.
    """
    t = np.linspace(0.0, 1.0, POINTS)
    best = np.full(lo.size, -np.inf)
    at = lo.copy()
    for _ in range(ROUNDS):
        x = lo[:, None] + (hi - lo)[:, None] * t  # (B, POINTS)
        fx = np.nan_to_num(f(x.ravel()).reshape(x.shape), nan=-np.inf)
        j = np.argmax(fx, axis=1)
        rows = np.arange(lo.size)
        better = fx[rows, j] > best
        best, at = np.where(better, fx[rows, j], best), np.where(better, x[rows, j], at)
        step = (hi - lo) / (POINTS - 1)
        lo, hi = np.maximum(lo, x[rows, j] - step), np.minimum(hi, x[rows, j] + step)
    return best, at


def worst_values(a) -> dict[str, Worst | None]:
    """Worst value of each quantity in QUANTITIES over the rise and fall curves of
    ``a`` (a camcore.analysis.Analysis), between the grid samples too; None where no
    face drives a rise or fall."""
    mask, th, n = a.on_curve, a.theta, a.theta.size
    rows = []  # (quantity number, face, grid index)
    with np.errstate(all="ignore"):
        for qi, (get, sense) in enumerate(QUANTITIES.values()):
            rows += [(qi, i, k) for i, k in _candidates(sense * get(a), mask)]
        if not rows:
            return dict.fromkeys(QUANTITIES)
        q, face, k = (np.array(c, dtype=int) for c in zip(*rows, strict=True))
        # the bracket: the grid neighbours where the same face still drives the curve
        has_lo = (k > 0) & mask[face, np.maximum(k - 1, 0)]
        has_hi = (k < n - 1) & mask[face, np.minimum(k + 1, n - 1)]
        lo = np.where(has_lo, th[np.maximum(k - 1, 0)], th[k])
        hi = np.where(has_hi, th[np.minimum(k + 1, n - 1)], th[k])
        getters = list(QUANTITIES.values())
        sense = np.array([s for _, s in getters])[q]

        def f(x):  # sense * quantity at x: POINTS angles per bracket, bracket-major
            loc = a.local(x)
            per = x.size // q.size
            vals = np.stack([get(loc) for get, _ in getters])  # (Q, F, len(x))
            return (
                np.repeat(sense, per)
                * vals[np.repeat(q, per), np.repeat(face, per), np.arange(x.size)]
            )

        grid = sense * np.stack([get(a) for get, _ in getters])[q, face, k]
        best, at = zoom(f, lo, hi)
        better = np.nan_to_num(best, nan=-np.inf) > grid
        best, at = np.where(better, best, grid), np.where(better, at, th[k])
    out: dict[str, Worst | None] = {}
    for j, name in enumerate(QUANTITIES):
        m = np.flatnonzero(q == j)
        if m.size == 0:
            out[name] = None
            continue
        b = m[np.argmax(best[m])]
        s = sense[b]
        out[name] = Worst(
            float(s * best[b]),
            float(at[b]),
            int(face[b]),
            tuple((float(s * best[i]), float(lo[i]), float(hi[i])) for i in m),
        )
    return out


def refine_maxes(f, theta: np.ndarray, values: list[np.ndarray]) -> list[tuple[float, float]]:
    """The maximum of each of Q closed-form quantities over the cycle, between the
    samples too, in one search: ``f`` maps cam angles x [rad] to the (Q, len(x)) values
    of all of them (one evaluation of the closed forms serves every bracket), ``values``
    holds each quantity on the grid ``theta``. The CANDIDATES largest local maxima of
    each quantity's samples are searched between their grid neighbours (the same zoom
    as worst_values). Returns (value, angle [rad]) per quantity; -inf where no sample is
    finite."""
    out: list[tuple[float, float]] = [(-np.inf, float("nan"))] * len(values)
    with np.errstate(all="ignore"):
        q, k = [], []
        for j, v in enumerate(values):
            cand = [kk for _, kk in _candidates(v[None, :], np.isfinite(v)[None, :])]
            q += [j] * len(cand)
            k += cand
        if not k:
            return out
        qa, ka = np.array(q), np.array(k)
        lo = theta[np.maximum(ka - 1, 0)]
        hi = theta[np.minimum(ka + 1, theta.size - 1)]

        def g(x):  # the quantity of each bracket at its POINTS angles, bracket-major
            per = x.size // qa.size
            return f(x)[np.repeat(qa, per), np.arange(x.size)]

        best, at = zoom(g, lo, hi)
        grid = np.array([values[j][kk] for j, kk in zip(qa, ka, strict=True)])
        best = np.fmax(best, grid)  # the zoom never loses the sample itself
        at = np.where(best > grid, at, theta[ka])
    for j in range(len(values)):
        m = np.flatnonzero(qa == j)
        if m.size:
            i = m[np.argmax(best[m])]
            out[j] = (float(best[i]), float(at[i]))
    return out
