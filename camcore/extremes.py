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

from .forces import jammed
from .motion import MOTIONS

ROUNDS = 3  # zoom rounds: each samples POINTS per bracket in one evaluation
POINTS = 33  # a 16-fold zoom per round: 4096-fold in all (3 evaluations, not 4)
CANDIDATES = 4  # local extremes refined per quantity and face (the worst first)

# name -> (per-face quantity of a camcore.analysis.Local, +1 maximize / -1 minimize)
QUANTITIES = {
    "pressure_angle_max": (lambda loc: np.abs(loc.pressure_angle), 1.0),  # [rad]
    "kappa_pitch_max": (lambda loc: loc.kappa_pitch, 1.0),  # [1/m]
    "kappa_pitch_min": (lambda loc: loc.kappa_pitch, -1.0),
    # the flat face's rho = r_b + S + S'' (1 / kappa_p): smooth where kappa_p is not, so a
    # dip of rho just below 0 between two samples is a minimum here, where in kappa_p
    # it was a maximum and went unsearched (an adversarial review: a cusp passed at 0.1
    # deg, rho -0.00055 mm over 0.03 deg)
    "pitch_radius_min": (lambda loc: 1.0 / loc.kappa_pitch, -1.0),  # [m]
    "FN_min": (lambda loc: loc.FN, -1.0),  # [N]
    "FN_max": (lambda loc: loc.FN, 1.0),
    "F1_max": (lambda loc: np.broadcast_to(loc.guide.F1, loc.FN.shape), 1.0),  # [N], guide
    "F2_max": (lambda loc: np.broadcast_to(loc.guide.F2, loc.FN.shape), 1.0),
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
    segments: tuple[int, ...] = ()  # the kind of segment (motion.RISE ...) of each of
    # ``others``: its grid sample's, under its face

    def within(self, code: int, sense: float) -> float | None:
        """The worst, in ``sense`` (QUANTITIES), of the refined extremes on segments of
        kind ``code`` (RISE, FALL); None if none is there."""
        values = [v for (v, _, _), c in zip(self.others, self.segments, strict=True) if c == code]
        if not values:
            return None
        return max(values) if sense > 0 else min(values)

    def beyond(self, limit: float, sense: float) -> tuple[tuple[float, float], ...]:
        """Brackets [rad] of the refined extremes that pass ``limit`` (sense as above)."""
        return tuple((lo, hi) for v, lo, hi in self.others if sense * (v - limit) > 0)


def top_peaks(values: np.ndarray, mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(row, grid index) of the CANDIDATES highest local maxima of each row of
    ``values`` (R, N) among the samples in ``mask``, row by row, the higher first and,
    between equal ones, the earlier; a maximum's height is what it may reach between
    its neighbours (_between), not its sample's. A plateau (a dwell) is a run of
    maxima: the C-th largest value is found by partition, then the earliest of its ties
    fill up."""
    C = CANDIDATES
    # not below either neighbour in the mask (none beyond the ends); boolean temporaries
    # only (a float one the size of a batch is a fresh mmap, page faults and all)
    peak = mask & np.isfinite(values)
    peak[:, 1:] &= (values[:, 1:] >= values[:, :-1]) | ~mask[:, :-1]
    peak[:, :-1] &= (values[:, :-1] >= values[:, 1:]) | ~mask[:, 1:]
    many = np.count_nonzero(peak) > 4 * C * values.shape[0]
    if many:  # (a dwell's plateau, mostly: its samples past the first C go first)
        peak = _first_of_ties(values, peak, C)
        many = np.count_nonzero(peak) > 4 * C * values.shape[0]
    row, k = np.nonzero(peak)
    rank = _between(values, mask, row, k)
    if many and values.shape[1] > C:  # many peaks: keep only the C highest of each row first
        pv = np.full(values.shape, -np.inf)
        pv[row, k] = rank
        kth = np.partition(pv, values.shape[1] - C, axis=1)[:, -C][:, None]  # C-th largest
        above = peak & (pv > kth)
        tie = peak & (pv == kth)
        room = C - above.sum(axis=1, keepdims=True)
        keep = (above | (tie & (np.cumsum(tie, axis=1) <= room)))[row, k]
        row, k, rank = row[keep], k[keep], rank[keep]
    order = np.lexsort((k, -rank, row))  # by row, then the peak between down, then index
    row, k = row[order], k[order]
    keep = np.arange(row.size) - np.searchsorted(row, row, side="left") < C
    return row[keep], k[keep]


def _between(values: np.ndarray, mask: np.ndarray, row: np.ndarray, k: np.ndarray):
    """The peak each local maximum k of ``values`` may reach between its neighbours: the
    vertex of the parabola through the three samples where k is above both, raised by
    at most what the lower neighbour lies below it (a parabola's vertex within half a
    step cannot pass that); the sample itself where it ties a neighbour.
    Peaks are ranked by it, not by the sample: five peaks alike to 1e-5 deg had the
    true worst in the fifth bracket, unsearched, and the verdict changed with the
    resolution (an adversarial review)."""
    n = values.shape[1]
    v0 = values[row, k]
    left, right = np.maximum(k - 1, 0), np.minimum(k + 1, n - 1)
    vl = np.where((k > 0) & mask[row, left], values[row, left], v0)
    vr = np.where((k < n - 1) & mask[row, right], values[row, right], v0)
    vl, vr = np.where(np.isfinite(vl), vl, v0), np.where(np.isfinite(vr), vr, v0)
    bend = 2.0 * v0 - vl - vr
    strict = (v0 > vl) & (v0 > vr)  # (a plateau's sample, a dwell's, stays as it is)
    with np.errstate(all="ignore"):
        rise = np.where(strict, (vr - vl) ** 2 / (8.0 * bend), 0.0)
    return v0 + np.clip(rise, 0.0, v0 - np.minimum(vl, vr))


def _first_of_ties(values: np.ndarray, peak: np.ndarray, c: int) -> np.ndarray:
    """``peak`` without the samples of a run of equal peaks (a plateau: a dwell) past
    its first ``c``: between equal values the earlier wins, so those can never be among
    a row's c largest. A dwell's thousand samples then cost the sort nothing (they
    made top_peaks a tenth of a sweep)."""
    tied = np.zeros_like(peak)
    tied[:, 1:] = peak[:, 1:] & peak[:, :-1] & (values[:, 1:] == values[:, :-1])
    if not tied.any():
        return peak
    idx = np.arange(values.shape[1])
    start = np.maximum.accumulate(np.where(tied, 0, idx), axis=1)  # its run's first
    return peak & (idx - start < c)


def distinct_rows(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The distinct rows of ``x`` (brackets, POINTS) and, per row of x, its row among
    them: brackets of several quantities often sample the very same angles (a stress
    peak where F_N peaks), and the closed forms need evaluating there once. (The batch
    uses it; worst_values tells one design's brackets apart by their two ends, which
    costs less than this sort of whole rows.)"""
    rows, inv = np.unique(x, axis=0, return_inverse=True)
    return rows, inv.reshape(-1)


def brackets(theta: np.ndarray, k: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The bracket [rad] of each candidate sample k of the grid ``theta`` (one turn,
    increasing from 0): its two neighbours around the circle (the first sample's lower
    one is the last minus 2 pi, the last's upper one the first plus 2 pi), also where a
    neighbour is on another segment or contact window: the search then counts only the
    angles where the face still drives a curve (``on_curve``). So the interval between
    a rise's last sample and its end is searched: a supremum can be there only (F_N,
    where guide friction acts until the follower stops at the end of a rise: 0.24 %
    above the last sample's for the paper's double rollers)."""
    n, two_pi = theta.size, 2 * np.pi
    first, last = theta[np.maximum(k - 1, 0)], theta[np.minimum(k + 1, n - 1)]
    if not whole_turn(theta):  # angles a caller chose (analyze's theta): never beyond them
        return first, last
    lo = np.where(k > 0, first, theta[-1] - two_pi)
    hi = np.where(k < n - 1, last, theta[0] + two_pi)
    return lo, hi


def whole_turn(theta: np.ndarray) -> bool:
    """Whether the increasing angles ``theta`` [rad] go round one turn with no gap
    wider than their widest step (the design's grid does; a caller's part does not)."""
    if theta.size < 2:
        return False
    steps = np.diff(theta)
    gap = theta[0] + 2 * np.pi - theta[-1]
    return bool(np.all(steps > 0) and 0 < gap <= steps.max() * (1 + 1e-9))


def on_curve(loc, codes: np.ndarray) -> np.ndarray:
    """(F, M) where each face of ``loc`` (an analysis.Local) touches a rise or fall;
    ``codes``: the segment code of each profile piece (motion.Segment.code)."""
    return loc.in_contact & np.isin(codes[loc.part], MOTIONS)


def peak(a, name: str, grid: float | None) -> float | None:
    """A figure's grid extreme ``grid`` of quantity ``name`` (QUANTITIES, in its SI
    unit) made the worst of it and the refined value between the samples
    (``a.worst``), so that a figure the report prints is the one the checks judge.
    None stays None (no sample to judge)."""
    w = a.worst.get(name)
    if grid is None or w is None or not np.isfinite(w.value):
        return grid
    return float(max(grid, w.value) if QUANTITIES[name][1] > 0 else min(grid, w.value))


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


def jams(loc, on: np.ndarray) -> np.ndarray:
    """(M,) where the guide of ``loc`` jams (forces.jammed) on a rise or fall."""
    return on.any(axis=0) & jammed(loc.guide)


def jam_worst(angles: np.ndarray, jammed_at: np.ndarray) -> Worst | None:
    """The guide's jams [rad] among the angles the search and the grid evaluated
    (``jammed_at`` says where the guide jams, extremes.jams), as a Worst of value 1
    whose brackets are the jams; None for none. Toward a jam the forces grow without
    bound, so the searches of F_N, F1 and F2 zoom in on its edge and meet the jam
    itself (an adversarial review: a jam 0.016 deg wide between two samples had passed
    at 0.1 deg, its 9.6e10 N printed as a figure). Jammed angles with no free one
    evaluated between them are one jam: by a fixed gap instead, the search's points
    at a jam's edge, 0.0125 deg apart on a 0.2 deg grid, had each stood as a jam of its
    own beside the grid's run (a physics review: "43.309-43.325, 43.337, 43.35,
    43.363 deg (+8 more)" for one jam of 43.3-58.1 deg)."""
    at, first = np.unique(np.mod(angles, 2 * np.pi), return_index=True)
    bad = jammed_at[first]
    if not bad.any():
        return None
    edges = np.flatnonzero(np.diff(np.concatenate([[0], bad.astype(np.int8), [0]])))
    runs = [(float(at[i]), float(at[j - 1])) for i, j in zip(edges[::2], edges[1::2], strict=True)]
    return Worst(1.0, runs[0][0], 0, tuple((1.0, lo, hi) for lo, hi in runs))


def worst_values(a) -> dict[str, Worst | None]:
    """Worst value of each quantity in QUANTITIES over the rise and fall curves of
    ``a`` (a camcore.analysis.Analysis), between the grid samples too; None where no
    face drives a rise or fall."""
    mask, th = a.on_curve, a.theta
    getters = list(QUANTITIES.values())
    with np.errstate(all="ignore"):
        found = []  # per quantity: (face, grid index, sense * value) of its candidates
        for get, s in getters:
            values = s * get(a)
            face, k = top_peaks(values, mask)
            found.append((face, k, values[face, k]))
        q = np.concatenate([np.full(f.size, i) for i, (f, _, _) in enumerate(found)])
        if q.size == 0:
            return dict.fromkeys(QUANTITIES)
        face, k, grid = (np.concatenate([c[i] for c in found]) for i in range(3))
        lo, hi = brackets(th, k)
        sense = np.array([s for _, s in getters])[q]

        codes = np.array([g.code for g in a.segments], dtype=np.int8)
        segment = codes[a.part]  # (F, N) the kind of segment under each face
        # every angle evaluated, grid and search, and whether the guide jams there
        seen, jammed = [th], [jams(a, a.on_curve)]

        def f(x):  # sense * quantity at x: POINTS angles per bracket, bracket-major
            per = x.size // q.size
            rows = x.reshape(q.size, per)
            # brackets of several quantities are often the same (F_N, F1, F2 and the
            # stress peak together): each evaluated once (a bracket is its two ends)
            _, first, inv = np.unique(
                rows[:, 0] + 1j * rows[:, -1], return_index=True, return_inverse=True
            )
            loc = a.local(rows[first].ravel())
            vals = np.stack([get(loc) for get, _ in getters])  # (Q, F, distinct x)
            fc = np.repeat(face, per)
            col = (inv.reshape(-1)[:, None] * per + np.arange(per)).ravel()
            out = np.repeat(sense, per) * vals[np.repeat(q, per), fc, col]
            on = on_curve(loc, codes)
            seen.append(rows[first].ravel())
            jammed.append(jams(loc, on))
            return np.where(on[fc, col], out, -np.inf)

        best, at = zoom(f, lo, hi)
        better = np.nan_to_num(best, nan=-np.inf) > grid
        best, at = np.where(better, best, grid), np.where(better, at, th[k])
    jam = jam_worst(np.concatenate(seen), np.concatenate(jammed))
    out: dict[str, Worst | None] = {"guide_jam": jam}
    for j, name in enumerate(QUANTITIES):
        m = np.flatnonzero(q == j)
        if m.size == 0:
            out[name] = None
            continue
        b = m[np.argmax(best[m])]
        s = sense[b]
        out[name] = Worst(
            float(s * best[b]),
            float(at[b] % (2 * np.pi)),  # (a bracket may cross theta = 0)
            int(face[b]),
            tuple((float(s * best[i]), float(lo[i]), float(hi[i])) for i in m),
            tuple(int(segment[face[i], k[i]]) for i in m),
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
        grid_values = np.stack(values)
        qa, ka = top_peaks(grid_values, np.isfinite(grid_values))
        if not ka.size:
            return out
        lo, hi = brackets(theta, ka)

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
            out[j] = (float(best[i]), float(at[i] % (2 * np.pi)))
    return out
