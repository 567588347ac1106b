"""The running machine (rigid follower): which spring, how fast, what the shaft delivers.

All of it follows from the load of Eq. 29, F_t = M (g + A w^2) + k (S + s_p) + F_e (F_e:
dynamics.external_load_N, beyond the paper, 0 in it), and the guide solve of Eqs.
33-41. That solve is linear and homogeneous in F_t (forces.py), and in every guide mode
it takes F_N has the sign of F_t (a mode where it does not is a wedge, not a
balance). So the follower keeps contact (F_N >= 0) exactly where

    k (S + s_p) >= -D,   D = M (g + A w^2) + F_e   (the load without the spring)

whatever the guide friction. This gives, as closed forms over the cam angle (their
extremes found between the grid samples, camcore.extremes.refine_maxes):

* the smallest spring rate for the design's preload, and the smallest preload for its
  rate;
* the jump speed: w^2 <= (M g + F_e + k (S + s_p)) / (-M A) wherever A < 0 (none at
  all where M g + F_e + k (S + s_p) < 0: a load pulling the follower off);
* a proposed spring (rule below), which meets limits.min_jump_speed_ratio too when set.

The shaft torque comes from the contact forces (forces.cam_torque); its peaks, the
power, and the energy a flywheel must buffer follow from it.

Spring rule (the usual one for force-closed cams, e.g. Norton, *Design of Machinery*,
cam dynamics chapter): the spring force must exceed the force that just keeps contact
by a safety factor n at every angle. Keeping the design's preload length s_p, the rate
n k_min does this, since n k_min (S + s_p) >= n (-D) everywhere.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import extremes, forces, motion
from .model import Design, omega_rad_s
from .units import MM, RPM


def spring_free_load(design: Design, prog: motion.Program) -> np.ndarray:
    """D = M (g + A w^2) + F_e [N]: the load F_t of Eq. 29 without the spring."""
    return forces.inertia_load(design, prog.A) + forces.external_load(design)


def spring_force(design: Design, prog: motion.Program) -> np.ndarray:
    """k (S + s_p) [N]: the spring's share of Eq. 29."""
    return forces.spring_load(design, prog.S)


def _over(num: np.ndarray, den: np.ndarray) -> np.ndarray:
    """num / den where num > 0 (inf where den <= 0 there), 0 where num <= 0."""
    with np.errstate(all="ignore"):  # overflow to inf is the right answer too
        return np.where(num > 0, np.where(den > 0, num / den, np.inf), 0.0)


def _sups(
    design: Design, theta: np.ndarray, per_programs: list, prog: motion.Program | None = None
) -> list[tuple[float, float]]:
    """Sup over the cycle of each per_program(program) (>= 0), between samples too, in
    one search (one program evaluation per zoom round serves all); ``prog`` is the
    program on ``theta`` if the caller has it already."""
    segs = motion.segments(design)
    prog = motion.program(design, theta, segs) if prog is None else prog
    grids = [fn(prog) for fn in per_programs]

    def f(x):
        p = motion.program(design, x, segs)
        return np.stack([fn(p) for fn in per_programs])

    found = extremes.refine_maxes(f, theta, grids)
    drop = velocity_drop(segs)
    out = []
    for grid, (value, at) in zip(grids, found, strict=True):
        if drop is not None:  # every need here grows with -A: unbounded at the drop
            out.append((np.inf, drop))
        elif np.isinf(grid).any():  # unbounded: no finite value will do
            out.append((np.inf, float(theta[np.argmax(grid)])))
        else:
            out.append((max(value, 0.0), at))
    return out


def velocity_drop(segs: tuple[motion.Segment, ...]) -> float | None:
    """The cam angle [rad] of the program's first instant drop in V (a velocity jump
    down: A = -inf there, e.g. a constant-velocity rise's end), or None. There the
    follower leaves the cam at any speed and no spring holds it: the needs of the spring
    and the jump speed are unbounded (the grid's samples miss the impulse: a teacher's
    review read 'jumps at 2411 rpm' for such a cam at 1200 rpm). A jump up is the cam
    pushing (an infinite force, not a jump)."""
    drops = [at for at, what, jump in motion.continuity_jumps(segs) if what == "V" and jump < 0]
    return min(drops) if drops else None


def _rate_need(design: Design):
    """k that keeps contact at each angle, given the preload (spring_rate_min)."""
    s_p = design.dynamics.preload_mm * MM
    return lambda p: _over(-spring_free_load(design, p), p.S + s_p)


def _preload_need(design: Design):
    """s_p that keeps contact at each angle, given the rate (preload_min)."""
    k = design.dynamics.spring_rate_N_per_m

    def need(p):
        D = spring_free_load(design, p)
        if k == 0.0:
            return np.where(D < 0, np.inf, 0.0)
        with np.errstate(over="ignore"):  # a vanishing rate needs an infinite preload
            return np.maximum(-D / k - p.S, 0.0)

    return need


def _jump_need(design: Design):
    """1 / w^2 at which F_N reaches zero at each angle (jump_speed_rpm)."""
    d = design.dynamics
    M, k, s_p = forces.moving_mass(design), d.spring_rate_N_per_m, d.preload_mm * MM
    hold = M * d.gravity_m_s2 + forces.external_load(design)  # (weight and F_e alike)

    def need(p):
        den = hold + k * (p.S + s_p)
        # where the static load pulls the follower off (F_e < 0 can), it leaves at any
        # speed: inf (a review: _over gave 0 there wherever A >= 0, a finite jump speed)
        return np.where(den < 0, np.inf, _over(-M * p.A, den))

    return need


def _rpm(inv_w2: float) -> float:
    return np.inf if inv_w2 == 0.0 else float(1.0 / np.sqrt(inv_w2) / RPM)


def spring_rate_min(
    design: Design, theta: np.ndarray, prog: motion.Program | None = None
) -> tuple[float, float]:
    """The smallest spring rate k [N/m] that keeps contact with the design's preload,
    and the cam angle [rad] that sets it; inf if no rate does (the follower must be
    pulled back where the spring is not compressed, S + s_p = 0)."""
    return _sups(design, theta, [_rate_need(design)], prog)[0]


def preload_min(
    design: Design, theta: np.ndarray, prog: motion.Program | None = None
) -> tuple[float, float]:
    """The smallest preload s_p [m] that keeps contact with the design's spring rate,
    and the angle [rad] that sets it; inf if none does (k = 0 and D < 0 somewhere)."""
    return _sups(design, theta, [_preload_need(design)], prog)[0]


def jump_speed_rpm(
    design: Design, theta: np.ndarray, prog: motion.Program | None = None
) -> tuple[float, float]:
    """The cam speed [rpm] at which F_N first reaches zero with the design's spring, and
    the angle [rad] where it does; inf if the follower never leaves the cam (no
    deceleration anywhere).

    F_t = M g + F_e + k (S + s_p) + M A w^2 >= 0 fails first where (-M A) / (M g + F_e +
    k (S + s_p)) is largest (A < 0 pulls the follower off; so does a negative F_e larger
    than the weight and spring hold: then at any speed, 0 rpm)."""
    inv_w2, at = _sups(design, theta, [_jump_need(design)], prog)[0]
    return _rpm(inv_w2), at


@dataclass(frozen=True)
class Shaft:
    """What the cam shaft must deliver at the design speed."""

    torque: np.ndarray  # (N,) driving torque [N m] on the analysis grid
    drive_max: float  # largest driving torque [N m] (>= 0), between samples too
    brake_max: float  # largest braking torque [N m] (>= 0): the follower drives the cam
    power_max: float  # largest power the shaft delivers [W]
    power_mean: float  # mean power [W]: the losses (guide friction); 0 without friction
    flywheel_energy: float  # energy fluctuation Delta E [J] about the mean torque
    flywheel_inertia: float  # inertia [kg m^2] for the design's speed fluctuation C_s


def shaft(a) -> Shaft:
    """Torque, power and flywheel figures of ``a`` (a camcore.analysis.Analysis).

    Delta E = max - min of the integral of (T - T_mean) over the cam angle; a flywheel
    of inertia I = Delta E / (C_s w^2) keeps the speed within C_s (the classic
    flywheel sizing, e.g. Shigley, *Mechanical Engineering Design*, flywheels)."""
    w = omega_rad_s(a.design)
    T = a.torque.sum(axis=0)
    th = np.append(a.theta, a.theta[0] + 2 * np.pi)
    cuts = steps_of(a.segments)
    cum = cycle_work(a.theta[None], T[None], np.ones((1, T.size), bool), cuts)[0]
    cum += impulse_work(a.design, th)
    T_mean = cum[-1] / (2 * np.pi)
    energy = cum - T_mean * (th - th[0])
    delta_E = float(energy.max() - energy.min())
    hi, lo = a.worst.get("torque_max"), a.worst.get("torque_min")
    drive = max(float(T.max()), hi.value if hi else 0.0, 0.0)
    brake = max(-float(T.min()), -lo.value if lo else 0.0, 0.0)
    c_w2 = a.design.dynamics.speed_fluctuation * w**2
    inertia = delta_E / c_w2 if c_w2 > 0 else np.inf  # a crawling cam: no flywheel helps
    return Shaft(T, drive, brake, drive * w, float(T_mean) * w, delta_E, inertia)


def steps_of(segs: tuple[motion.Segment, ...]) -> np.ndarray:
    """The cam angles [rad] where the program's V or A steps (a segment's end and the
    next one's start differ): where the torque can step (cycle_work)."""
    out = []
    for i, g in enumerate(segs):
        after = segs[(i + 1) % len(segs)]
        if not np.allclose(g.ends()[2:], after.ends()[:2], rtol=1e-9, atol=1e-12):
            out.append(after.start)
    return np.array(out)


def cycle_work(theta: np.ndarray, T: np.ndarray, real: np.ndarray, cuts) -> np.ndarray:
    """The work of the torque T [N m] from the first angle on, (B, N + 1) [J]: trapezoids
    over each grid of ``theta`` (B, N) [rad] closed at 2 pi on (``real``: False on a
    padding, which repeats a grid's last angle).

    The torque can step where the program's V or A steps (``cuts`` [rad], steps_of),
    and a grid's sample there holds one side's value. So the trapezoids on either side
    of such a sample use the value extrapolated from their own side (the two samples
    before, or after), unless a neighbour is on a cut too. Without this the trapezoid
    lost half a step's strip per jump: a frictionless constant-velocity rise's mean
    power was 0.026 W at 0.1 deg, not 0 (a review). Only there: where nothing steps
    the plain trapezoid is the better (a review: -1.2e-4 W at 1 deg on the smooth
    paper example, where the trapezoid gives 1e-15)."""
    B, N = T.shape
    n = real.sum(axis=1)  # each grid's real samples
    cut = real & (np.abs(theta[..., None] - np.mod(cuts, 2 * np.pi)) < 1e-12).any(axis=-1)
    left, right = T.copy(), T.copy()  # T just before, and just after, each sample
    b, i = np.nonzero(cut)
    for side, out in ((-1, left), (1, right)):
        j1, j2 = (i + side) % n[b], (i + 2 * side) % n[b]
        ok = ~cut[b, j1] & ~cut[b, j2] & (n[b] > 2)
        t0 = theta[b, i]
        # the neighbours' angles on their side of t0 (a grid wraps at 2 pi)
        t1 = theta[b, j1] + 2 * np.pi * side * ((j1 - i) * side < 0)
        t2 = theta[b, j2] + 2 * np.pi * side * ((j2 - i) * side < 0)
        with np.errstate(divide="ignore", invalid="ignore"):
            ext = T[b, j1] + (T[b, j1] - T[b, j2]) * (t0 - t1) / (t1 - t2)
        out[b[ok], i[ok]] = ext[ok]
    right = np.where(real, right, right[np.arange(B), n - 1][:, None])  # (the padding)
    th = np.concatenate([theta, theta[:, :1] + 2 * np.pi], axis=1)
    ends = np.concatenate([left[:, 1:], left[:, :1]], axis=1)  # each step's far end
    steps = 0.5 * (right + ends) * np.diff(th, axis=1)
    return np.concatenate([np.zeros((B, 1)), np.cumsum(steps, axis=1)], axis=1)


def impulse_work(design: Design, th: np.ndarray) -> np.ndarray:
    """The work the shaft does in the impulses of a velocity jump [J], accumulated over
    the cam angles ``th`` [rad] (after each jump): the follower's kinetic energy steps
    by M w^2 (V+^2 - V-^2) / 2 there, which no sample of the torque carries (a dynamics
    review: the flywheel's Delta E of a constant-velocity rise was 4.6 % low and the
    frictionless mean power 0.026 W, not 0). The guide friction during the impulse is
    not in it; such a cam breaks velocity_jump anyway. Zeros without a jump."""
    out = np.zeros_like(th)
    segs = motion.segments(design)
    M, w = forces.moving_mass(design), omega_rad_s(design)
    for i, g in enumerate(segs):
        v_before, v_after = g.ends()[2], segs[(i + 1) % len(segs)].ends()[0]
        if v_before != v_after:
            out[th > g.end % (2 * np.pi)] += 0.5 * M * w**2 * (v_after**2 - v_before**2)
    return out


@dataclass(frozen=True)
class Spring:
    """The spring figures of a design (see the module docstring for the rule)."""

    rate_min: float  # [N/m] with the design's preload (inf: none suffices)
    rate_min_at: float  # [rad]
    preload_min: float  # [m] with the design's rate (inf: none suffices)
    jump_speed_rpm: float  # inf: never jumps
    jump_at: float  # [rad]
    safety_factor: float
    proposed_rate: float  # [N/m] at the design's preload, rounded up (proposal)
    margin_rate: float | None  # [N/m] k_min at limits.min_jump_speed_ratio x the speed
    # (the design's preload; None without that limit)


def margin_rate_need(design: Design):
    """The rate need (spring_rate_min's) of ``design`` run at limits.min_jump_speed_ratio
    times its speed, None without that limit: the spring that keeps contact up to the
    margin (checks' jump_speed)."""
    m = design.limits.min_jump_speed_ratio
    if m is None:
        return None
    cam = design.cam.model_copy(update={"speed_rpm": m * design.cam.speed_rpm})
    return _rate_need(design.model_copy(update={"cam": cam}))


def proposal(n: float, k_min: float, margin_rate: float | None) -> float:
    """The spring rate to propose [N/m]: n k_min (the spring rule), and at least the rate
    the jump-speed margin asks, each rounded up (proposed_rate; a review: the proposal
    had broken the user's own margin)."""
    rate = proposed_rate(n, k_min)
    return rate if margin_rate is None else max(rate, proposed_rate(1.0, margin_rate))


def margins(design: Design, rate_min: float, jump_rpm: float) -> dict[str, float | None]:
    """How far the design is from jump, as ratios a designer compares with the
    spring's safety factor n: ``spring_rate`` = k / k_min and ``jump_speed`` = the jump
    speed / the running speed (both > 1 keeps contact; None where unbounded: no spring
    suffices, nothing pulls the follower off, or k_min = 0). Not a limit in itself (a
    design at 1.03 meets the spring rule's limits, only closer to jump than n asks);
    limits.min_jump_speed_ratio makes the second one (checks' jump_speed)."""
    k = design.dynamics.spring_rate_N_per_m
    rate = k / rate_min if 0.0 < rate_min < math.inf else math.inf
    speed = jump_rpm / design.cam.speed_rpm  # (a crawling cam's can overflow)
    return {
        n: float(x) if math.isfinite(x) else None
        for n, x in (("spring_rate", rate), ("jump_speed", speed))
    }


def spring(design: Design, theta: np.ndarray, prog: motion.Program | None = None) -> Spring:
    """Spring sizing and jump speed of ``design`` over the grid ``theta`` [rad] (``prog``:
    its program there, if at hand, e.g. an Analysis's)."""
    needs = [_rate_need(design), _preload_need(design), _jump_need(design)]
    margin = margin_rate_need(design)
    found = _sups(design, theta, needs + ([margin] if margin is not None else []), prog)
    (k_min, k_at), (s_min, _), (inv_w2, at) = found[:3]
    k_margin = found[3][0] if margin is not None else None
    n = design.dynamics.spring_safety_factor
    rate = proposal(n, k_min, k_margin)
    return Spring(k_min, k_at, s_min, _rpm(inv_w2), at, n, rate, k_margin)


PROPOSAL_DIGITS = 4
ROUND_OFF = 1e-9  # relative: a ratio this close to the safety factor meets it
EPS = float(np.finfo(float).eps)


def proposed_rate(n: float, k_min: float) -> float:
    """The spring rate to propose [N/m]: n k_min rounded up to PROPOSAL_DIGITS
    significant figures, so that the figure a user copies meets the safety factor (the
    exact 2089.334 shown as 2089.3 had read 'k = 1.49 k_min: close to jump' once typed
    in). Decimal digits, not binary arithmetic (0.001 stays 0.001; subnormal rates
    too); inf stays inf, 0 stays 0."""
    x = n * k_min
    if not math.isfinite(x) or x <= 0.0:
        return x
    mantissa, exponent = f"{x:.{PROPOSAL_DIGITS - 1}e}".split("e")  # the nearest 4 figures
    digits = round(float(mantissa) * 10 ** (PROPOSAL_DIGITS - 1))
    near = float(f"{digits}e{int(exponent) - PROPOSAL_DIGITS + 1}")
    if near >= x * (1 - 4 * EPS):  # (n k_min's own round-off: 3 x 0.1 is 0.3)
        return near if math.isfinite(near) else x
    up = float(f"{digits + 1}e{int(exponent) - PROPOSAL_DIGITS + 1}")  # the next up
    return up if math.isfinite(up) else x
