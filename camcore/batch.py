"""The batched core: many designs along a leading axis, one evaluation (issue 12).

A sweep asks the same question of thousands of designs that differ only in their
geometry: base radius, roller or face radius, the double follower's offset e, a
single follower's offset. Those designs share the motion program, the follower kind,
the dynamics and the materials, so their closed forms (Eqs. 1-21, 29-42) can be
evaluated for all of them at once: each design's geometry is an array entry (not a
Python scalar), each design keeps its own angle grid (the one ``analyze`` would use,
padded with its last angle to a common length), and everything is computed on the
flattened (design, angle) axis with one numpy call per formula.

Out come fixed-size figures per design: the grid maxima and ranges of the report
(``camcore report --json``, the same keys), the worst values between the samples
(the zoom search of camcore.extremes, batched), the shaft figures, and the verdict of
the paper's limits (camcore.checks, the same rules in the same order). What needs the
ragged profile is not built here: the profile's area, perimeter and vertices, its
chord error and the export tolerance, the star-shape check, the hub wall and the outer
diameter (a design with a bore or a diameter limit is not batched), wear along
the profile and the geometric check (``camcore.sweep`` runs those through the single analysis when
asked). What depends on neither the geometry nor the grid (the elastic train, the
program's continuity) is computed once per batch; the spring figures depend on the
grid (their search starts from its samples), so each design gets its own, in one
batched search. The numbers are the single analysis' (tested to 1e-15 relative).

Sliding faces with contact friction (mu_c > 0) are not batched: their force direction
depends on the slip (camcore.analysis._contact_slide). Nor are designs whose profile
a limit judges (a bore: the hub wall; limits.max_outer_diameter_mm): their verdict
needs the profile. ``batchable`` says so and the sweep falls back to the single
analysis for them.
"""

from __future__ import annotations

import copy
import json
import math
from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np

from . import checks, extremes, forces, machine, motion, profile, train
from .analysis import stations
from .contact import compliance, conservative_stress, half_width, hertz_line_stress
from .model import Design, allowable_contact_stress_MPa, contact_stress_limit_MPa, omega_rad_s
from .motion import FALL, HIGH, RISE
from .report import _finite, _train, unbounded_of
from .units import MM, to_deg

R2D = 180.0 / math.pi

# the fields a batch may vary (everything else of its designs must be equal)
BATCHED_FIELDS = (
    ("cam", "base_radius_mm"),
    ("follower", "roller_radius_mm"),
    ("follower", "face_radius_mm"),
    ("follower", "offset_mm"),
    ("follower", "single_offset_mm"),
)

# the violations this core cannot decide: they need the profile (module docstring)
PROFILE_CHECKS = (
    "profile_crossing",
    "export_tolerance",
    "hub_wall",
    "outer_diameter",
    "geometric_check",
)


def group_key(design: Design) -> str:
    """Designs with the same key can share a batch: all but BATCHED_FIELDS equal."""
    data = design.model_dump(mode="json")
    for block, name in BATCHED_FIELDS:
        data[block].pop(name, None)
    return json.dumps(data, sort_keys=True)


def batchable(design: Design) -> bool:
    """False where the batch would not give the single analysis' verdict: a sliding face
    (concave, flat, knife edge) with contact friction (its forces differ), and a design
    with a limit on its profile, a bore (the hub wall) or a largest outer diameter (a
    review: a --fast sweep's front offered cams past the user's own envelope as valid)."""
    kind = design.follower.kind
    sliding = design.dynamics.contact_friction > 0.0 and not kind.is_roller
    profile_limit = (
        design.cam.bore_diameter_mm > 0.0 or design.limits.max_outer_diameter_mm is not None
    )
    return not (sliding or profile_limit)


@dataclass(frozen=True)
class Batch:
    """B designs of one group: their geometry as arrays, their grids padded to N."""

    designs: tuple[Design, ...]
    segs: tuple[motion.Segment, ...]
    r: np.ndarray  # (B,) signed face radius [m] (+inf flat face, 0 knife edge)
    y0: np.ndarray  # (B,) Y_C at S = 0 [m] (Eq. 3)
    sigma: np.ndarray  # (B,)
    stem_x: np.ndarray  # (B,) [m]
    x_c: np.ndarray  # (B, F) face centre abscissae [m]
    arc: np.ndarray  # (B, n_segments, 3): start, end [rad] and psi of each dwell arc
    theta: np.ndarray  # (B, N) each design's grid, padded with its last angle
    real: np.ndarray  # (B, N) False on the padding
    geos: tuple[profile.Geometry, ...]
    stations: tuple[np.ndarray, ...]

    @property
    def flat(self) -> bool:
        return bool(np.isinf(self.r[0]))

    @property
    def n_faces(self) -> int:
        return self.x_c.shape[1]


def make_batch(designs: list[Design]) -> Batch:
    """The batch of ``designs``: all batchable, of one group_key and with the same
    number of faces (ValueError otherwise)."""
    d0 = designs[0]
    if not all(batchable(d) for d in designs):
        raise ValueError("a sliding face with contact friction, a bore or a diameter limit")
    if len({group_key(d) for d in designs}) != 1:
        raise ValueError(f"a batch holds designs that differ only in {BATCHED_FIELDS}")
    segs = motion.segments(d0)
    geos = [profile.geometry(d) for d in designs]
    if len({len(g.faces) for g in geos}) != 1:  # e = 0 makes a double follower single
        raise ValueError("a batch holds designs with the same number of faces")
    sts = [stations(d, g) for d, g in zip(designs, geos, strict=True)]
    grids = [motion.theta_grid(d, tuple(s)) for d, s in zip(designs, sts, strict=True)]
    n = max(g.size for g in grids)
    theta = np.stack([np.pad(g, (0, n - g.size), mode="edge") for g in grids])
    real = np.arange(n)[None, :] < np.array([g.size for g in grids])[:, None]
    arc = np.zeros((len(designs), len(segs), 3))
    for b, geo in enumerate(geos):
        for j, g in enumerate(segs):
            if not g.is_motion:
                arc[b, j] = (*profile.arc_span(geo, segs, j), profile.dwell_psi(geo, g.S0))
    return Batch(
        designs=tuple(designs),
        segs=segs,
        r=np.array([g.r for g in geos]),
        y0=np.array([g.y0 for g in geos]),
        sigma=np.array([g.sigma for g in geos]),
        stem_x=np.array([g.stem_x for g in geos]),
        x_c=np.array([[f.x_c for f in g.faces] for g in geos]),
        arc=arc,
        theta=theta,
        real=real,
        geos=tuple(geos),
        stations=tuple(sts),
    )


def _windows(bt: Batch, prog: motion.Program, which: np.ndarray):
    """profile.contact_windows with each angle's own design (``which``)."""

    def arc(j: int):
        return tuple(bt.arc[which, j, k] for k in range(3))

    return profile.windows_on_arcs(prog, bt.segs, bt.n_faces, arc)


def local(bt: Batch, theta: np.ndarray, which: np.ndarray) -> SimpleNamespace:
    """analysis.evaluate for many designs: at cam angles ``theta`` (M,) [rad], angle k
    belonging to design ``which[k]``. Per-face arrays are (F, M), SI units."""
    d0 = bt.designs[0]
    prog = motion.program(d0, theta, bt.segs)
    S, V, A = prog.S, prog.V, prog.A
    r, sigma, y0 = bt.r[which], bt.sigma[which], bt.y0[which]
    yc = y0 + S
    F, M = bt.n_faces, theta.size
    nrm, pw = np.empty((F, M, 2)), np.empty((F, M, 2))
    phi, k, lever = np.zeros((F, M)), np.empty((F, M)), np.empty((F, M))
    for i in range(F):
        if bt.flat:  # profile.face_contact, pitch_curvature, lever_x for a flat face
            nrm[i, :, 0], nrm[i, :, 1] = 0.0, 1.0
            pw[i, :, 0], pw[i, :, 1] = -V, yc
            with np.errstate(divide="ignore"):
                k[i] = 1.0 / (yc + A)
            lever[i] = -V - bt.stem_x[which]
            continue
        # Eqs. 3-10, 13-18 (profile.face_contact); the pitch curve's curvature, from
        # which rho (Eq. 21) follows by the parallel-curve relation (profile.pitch_curvature)
        x_c = bt.x_c[which, i]
        u = x_c + V
        m = np.hypot(u, yc)
        nx, ny = sigma * u / m, sigma * yc / m
        nrm[i, :, 0], nrm[i, :, 1] = nx, ny
        pw[i, :, 0], pw[i, :, 1] = x_c - r * nx, yc - r * ny
        phi[i] = np.arctan2(sigma * nx, ny)
        k[i] = (yc * yc + u * (u + V) - A * yc) / (yc * yc + u * u) ** 1.5
        lever[i] = x_c - bt.stem_x[which]
    r_face = np.zeros_like(r) if bt.flat else r  # profile.curvature_radius
    with np.errstate(divide="ignore"):
        rho = np.where(k == 0.0, np.inf, sigma / k - r_face)
    windows, part = _windows(bt, prog, which)
    Ft = forces.total_load(d0, S, A)  # Eqs. 29-30
    guide = forces.follower_forces(d0, Ft, windows, nrm, lever, r_face, S, V, None)
    FN = np.where(windows, guide.FN[None, :], 0.0)
    return SimpleNamespace(
        prog=prog,
        in_contact=windows,
        part=part,
        normal=nrm,
        point_world=pw,
        pressure_angle=phi,
        kappa_pitch=k,
        rho=rho,
        Ft=Ft,
        guide=guide,
        FN=FN,
        stress=_stress(d0, FN, rho, r),
        torque=forces.cam_torque(pw, nrm, FN),
    )


def _stress(d0: Design, FN, rho, r) -> np.ndarray:
    """contact.contact_stress (Eq. 42, conservative beyond Hertz's validity) with each
    angle's own follower radius r (M,)."""
    if d0.follower.radius_mm == 0.0:  # knife edge: not defined
        return np.full(np.shape(FN), np.nan)
    w = d0.cam.width_mm * MM
    plain = hertz_line_stress(FN, r, rho, w, compliance(d0))
    return conservative_stress(FN, plain, r, rho, w)[0]


def _on_curve(loc, segs) -> np.ndarray:
    return extremes.on_curve(loc, np.array([g.code for g in segs], dtype=np.int8))


def _quantities(bt: Batch) -> dict:
    """The quantities of extremes.QUANTITIES the verdict and figures of this kind need."""
    names = ["pressure_angle_max", "FN_min", "FN_max", "F1_max", "F2_max"]
    names += ["torque_max", "torque_min"]
    if bt.flat:
        names.append("pitch_radius_min")
    elif bt.r[0] > 0:
        names.append("kappa_pitch_max")
    elif bt.r[0] < 0:
        names.append("kappa_pitch_min")
    if bt.r[0] != 0.0:
        names.append("stress_max")
    return {n: extremes.QUANTITIES[n] for n in names}


def _brackets(th: np.ndarray, des: np.ndarray, k: np.ndarray, last: np.ndarray):
    """extremes.brackets of the candidates k of designs ``des`` on their own grids
    (rows of ``th``, real up to ``last``, the rest padding): a batch's grids are the
    designs' own, whole turns (extremes.whole_turn), so the brackets go round."""
    two_pi = 2 * np.pi
    lo = np.where(k > 0, th[des, np.maximum(k - 1, 0)], th[des, last[des]] - two_pi)
    hi = np.where(k < last[des], th[des, np.minimum(k + 1, last[des])], th[des, 0] + two_pi)
    return lo, hi


def _refine(bt: Batch, loc, on: np.ndarray) -> dict:
    """extremes.worst_values for every design at once: name -> (B, C) refined values of
    the candidates (C per design, NaN where there is none), in the quantity's sense."""
    B, N = bt.theta.shape
    F = bt.n_faces
    th = bt.theta
    mask = (on.reshape(F, B, N)) & bt.real[None]
    qs = _quantities(bt)
    rows = []  # per quantity: (face, design, grid index) of its candidates
    for get, sense in qs.values():
        row, k = extremes.top_peaks(sense * get(loc).reshape(F * B, N), mask.reshape(F * B, N))
        rows.append((row // B, row % B, k))
    q = np.concatenate([np.full(r[0].size, i) for i, r in enumerate(rows)])
    face, des, k = (np.concatenate([r[i] for r in rows]) for i in range(3))
    out = {n: np.full((B, F * extremes.CANDIDATES), np.nan) for n in [*qs, SEGMENT_OF_PHI]}
    if q.size == 0:
        return out
    kk = des * N + k
    last = bt.real.sum(axis=1) - 1  # each design's last real grid index (the rest pads)
    lo, hi = _brackets(th, des, k, last)
    getters = list(qs.values())
    sense = np.array([s for _, s in getters])[q]
    codes = np.array([g.code for g in bt.segs], dtype=np.int8)
    jammed = np.zeros(B, bool)  # designs whose guide the search met jammed

    def fz(x):  # sense * quantity at x: POINTS angles per bracket, bracket-major
        keyed = np.concatenate([des[:, None], x.reshape(q.size, -1)], axis=1)
        rows, inv = extremes.distinct_rows(keyed)  # (design, angles) evaluated once
        per = rows.shape[1] - 1
        at = local(bt, rows[:, 1:].ravel(), np.repeat(rows[:, 0].astype(int), per))
        vals = np.stack([get(at) for get, _ in getters])
        vals = vals.reshape(vals.shape[0], vals.shape[1], rows.shape[0], per)
        on = extremes.on_curve(at, codes)
        jams = extremes.jams(at, on).reshape(rows.shape[0], per).any(axis=1)
        jammed[rows[jams, 0].astype(int)] = True
        on_at = on.reshape(F, rows.shape[0], per)
        out = np.where(on_at[face, inv], sense[:, None] * vals[q, face, inv], -np.inf)
        return out.ravel()

    with np.errstate(all="ignore"):
        grid = np.empty(q.size)  # each quantity at its candidates (a stack of them all
        for i, (get, s) in enumerate(getters):  # on the grid had copied ~30 MB a chunk)
            m = q == i
            grid[m] = s * get(loc)[face[m], kk[m]]
        best, _ = extremes.zoom(fz, lo, hi)
        best = np.where(np.nan_to_num(best, nan=-np.inf) > grid, best, grid)
    key = q * B + des  # the candidate's column in its design's row: its rank in the run
    order = np.argsort(key, kind="stable")
    first = np.searchsorted(key[order], key[order], side="left")
    slot = np.empty(q.size, int)
    slot[order] = np.arange(q.size) - first
    for i, name in enumerate(qs):
        m = q == i
        out[name][des[m], slot[m]] = sense[m] * best[m]
    # the kind of segment of each pressure-angle candidate (extremes.Worst.segments)
    m = q == list(qs).index("pressure_angle_max")
    out[SEGMENT_OF_PHI][des[m], slot[m]] = codes[loc.part[face[m], kk[m]]]
    out["guide_jam"] = np.where(jammed, 1.0, np.nan)[:, None]  # (extremes.jam_worst)
    return out


def _max(x: np.ndarray, mask: np.ndarray | None = None) -> list[float | None]:
    """report._max per design: x is (B, ...) or (F, B, N) with the design on axis -2 if
    3-D; the largest non-NaN value under ``mask`` per design, None if there is none."""
    mask = np.ones(x.shape, bool) if mask is None else mask
    x = np.moveaxis(x, -2, 0) if x.ndim == 3 else x
    mask = np.moveaxis(mask, -2, 0) if mask.ndim == 3 else mask
    m = np.broadcast_to(mask, x.shape) & ~np.isnan(x)
    top = np.where(m, x, -np.inf).reshape(x.shape[0], -1).max(axis=1)
    has = m.reshape(x.shape[0], -1).any(axis=1)
    return [float(t) if h else None for t, h in zip(top, has, strict=True)]


def _min(x: np.ndarray, mask: np.ndarray) -> list[float | None]:
    return [None if v is None else -v for v in _max(-x, mask)]


def _range(x: np.ndarray, mask: np.ndarray) -> list[list[float] | None]:
    """report._range_mm per design: [min, max] under ``mask``, None if it is empty."""
    lo, hi = _min(x, mask), _max(x, mask)
    return [None if a is None or b is None else [a, b] for a, b in zip(lo, hi, strict=True)]


def _scaled(values: list[float | None], factor: float) -> list[float | None]:
    return [None if v is None else v * factor for v in values]


def _worst(cands: np.ndarray, sense: float) -> np.ndarray:
    """The worst refined value per design (NaN where there is no candidate)."""
    with np.errstate(all="ignore"):
        some = ~np.isnan(cands).all(axis=1)
        pick = np.nanmax if sense > 0 else np.nanmin
        out = np.full(cands.shape[0], np.nan)
        if some.any():
            out[some] = pick(cands[some], axis=1)
    return out


def _shaft(bt: Batch, T: np.ndarray, worst: dict) -> list[dict]:
    """machine.shaft per design: T (B, N) the driving torque on each grid."""
    d0 = bt.designs[0]
    w = omega_rad_s(d0)
    th = np.concatenate([bt.theta, bt.theta[:, :1] + 2 * np.pi], axis=1)
    cum = machine.cycle_work(bt.theta, T, bt.real, machine.steps_of(bt.segs))
    cum += machine.impulse_work(d0, th)  # (one program for the batch)
    T_mean = cum[:, -1] / (2 * np.pi)
    energy = cum - T_mean[:, None] * (th - th[:, :1])
    delta_E = energy.max(axis=1) - energy.min(axis=1)
    hi, lo = _worst(worst["torque_max"], 1.0), _worst(worst["torque_min"], -1.0)
    hi, lo = np.where(np.isnan(hi), 0.0, hi), np.where(np.isnan(lo), 0.0, lo)
    drive = np.maximum(np.maximum(T.max(axis=1), hi), 0.0)
    brake = np.maximum(np.maximum(-T.min(axis=1), -lo), 0.0)
    c_w2 = d0.dynamics.speed_fluctuation * w**2
    return [
        {
            "cam_torque_max_Nm": {"drive": float(drive[b]), "brake": float(brake[b])},
            "power_max_W": float(drive[b] * w),
            "power_mean_W": float(T_mean[b] * w),
            "flywheel_energy_J": float(delta_E[b]),
            "flywheel_inertia_kg_m2": _finite(delta_E[b] / c_w2 if c_w2 > 0 else np.inf),
        }
        for b in range(T.shape[0])
    ]


def _springs(bt: Batch, prog: motion.Program) -> list[dict]:
    """machine.spring for each design on its own grid (``prog``: the program on the
    flattened grids), in one search: the grid's sup of each need per design, refined
    between the samples as extremes.refine_maxes does, then machine._sups' rules."""
    d0 = bt.designs[0]
    B, N = bt.theta.shape
    needs = [machine._rate_need(d0), machine._preload_need(d0), machine._jump_need(d0)]
    margin = machine.margin_rate_need(d0)  # (limits.min_jump_speed_ratio: the group's)
    needs += [margin] if margin is not None else []
    grid = np.stack([fn(prog) for fn in needs]).reshape(len(needs) * B, N)
    with np.errstate(all="ignore"):
        row, k = extremes.top_peaks(grid, np.isfinite(grid) & np.tile(bt.real, (len(needs), 1)))
        q, des = row // B, row % B
        last = bt.real.sum(axis=1) - 1  # each design's last real grid index
        lo, hi = _brackets(bt.theta, des, k, last)

        def g(x):  # the need of each bracket at its POINTS angles, bracket-major
            p = motion.program(d0, x, bt.segs)
            per = x.size // q.size
            return np.stack([fn(p) for fn in needs])[np.repeat(q, per), np.arange(x.size)]

        best = extremes.zoom(g, lo, hi)[0] if q.size else np.zeros(0)
        best = np.fmax(best, grid[row, k])  # the zoom never loses the sample itself
    sup = np.full(len(needs) * B, -np.inf)
    np.maximum.at(sup, row, best)
    unbounded = np.isinf(np.where(bt.real[None], grid.reshape(len(needs), B, N), 0.0))
    sup = np.where(unbounded.any(axis=2).ravel(), np.inf, np.maximum(sup, 0.0))
    if machine.velocity_drop(bt.segs) is not None:  # machine._sups: A = -inf there
        sup[:] = np.inf
    k_min, s_min, inv_w2 = sup.reshape(len(needs), B)[:3]
    k_margin: list[float | None] = (
        [float(x) for x in sup.reshape(len(needs), B)[3]] if margin is not None else [None] * B
    )
    n = d0.dynamics.spring_safety_factor
    return [
        {
            "spring_rate_min_N_per_m": _finite(k_min[b]),
            "preload_min_mm": _finite(s_min[b], 1e3),
            "spring_proposal": {
                "safety_factor": n,
                "spring_rate_N_per_m": _finite(machine.proposal(n, float(k_min[b]), k_margin[b])),
                "preload_mm": d0.dynamics.preload_mm,
            },
            "jump_speed_rpm": _finite(machine._rpm(float(inv_w2[b]))),
            "jump_margin": machine.margins(
                bt.designs[b], float(k_min[b]), machine._rpm(float(inv_w2[b]))
            ),
        }
        for b in range(B)
    ]


def _group_figures(bt: Batch) -> tuple[dict | None, list[str], list[str]]:
    """What does not depend on the geometry (nor on the grid): the elastic train's
    figures, and the codes of the program's continuity and of the train's jump."""
    d0 = bt.designs[0]
    one = SimpleNamespace(design=d0, train=train.respond(d0))  # what the checks read
    continuity = [v.code for v in checks._continuity(one)]
    return _train(one), continuity, [v.code for v in checks._train(one)]  # type: ignore[arg-type]


def _verdicts(bt: Batch, loc, on: np.ndarray, worst: dict, group: tuple) -> list[list[str]]:
    """The codes of the violations of each design, as checks.run_all lists them (the
    same rules: on the grid, or at a refined extreme between the samples; ``group``:
    the codes of the program's continuity and of the elastic train), without the
    profile's own checks."""
    B, N = bt.theta.shape
    F = bt.n_faces
    d0 = bt.designs[0]
    on3 = on.reshape(F, B, N)
    k = loc.kappa_pitch.reshape(F, B, N)

    def grid_any(bad: np.ndarray) -> np.ndarray:  # (F, B, N) or (B, N) -> (B,)
        return np.asarray(bad.reshape(-1, B, N).any(axis=(0, 2)))

    def cand_any(name: str, test) -> np.ndarray:
        c = worst.get(name)
        with np.errstate(invalid="ignore"):
            return np.zeros(B, bool) if c is None else test(c).any(axis=1)

    codes: list[list[str]] = [[] for _ in range(B)]  # appended in run_all's order

    def add(bad: np.ndarray, code: str) -> None:
        for b in np.flatnonzero(bad):
            codes[b].append(code)

    r = bt.r[:, None]  # (B, 1)
    if bt.flat:
        add(
            grid_any(on3 & (k <= 0)) | cand_any("pitch_radius_min", lambda v: v <= 0),
            "curvature_convex",
        )
    elif bt.r[0] > 0:
        lim = 1.0 / r
        add(
            grid_any(on3 & (k >= lim)) | cand_any("kappa_pitch_max", lambda v: v > lim),
            "roller_undercut",
        )
    elif bt.r[0] < 0:
        lim = 1.0 / -r
        fold = grid_any(on3 & (k > 0) & (k <= lim)) | cand_any(
            "kappa_pitch_min", lambda v: (v > 0) & (v <= lim)
        )
        add(fold, "curvature_convex")
        add(
            grid_any(on3 & (k <= 0)) | cand_any("kappa_pitch_min", lambda v: v <= 0),
            "curvature_face",
        )
    limit = d0.limits.max_pressure_angle_deg  # Eqs. 5, 13
    phi = to_deg(np.abs(loc.pressure_angle))  # as checks._pressure_angle
    bad = grid_any(on & (phi > checks.most(limit))) | cand_any(
        "pressure_angle_max", lambda v: v > checks.most(math.radians(limit))
    )
    add(bad, "pressure_angle")
    if bt.r[0] != 0.0:  # Eq. 42
        lim_pa = checks.most(contact_stress_limit_MPa(d0) * 1e6)
        stress = np.where(loc.in_contact, loc.stress, 0.0)
        add(
            grid_any(stress > lim_pa) | cand_any("stress_max", lambda v: v > lim_pa),
            "contact_stress",
        )
    for b, (d, geo) in enumerate(zip(bt.designs, bt.geos, strict=True)):  # Eq. 28
        if F == 2:
            one = SimpleNamespace(geo=geo, design=d)
            codes[b] += [v.code for v in checks._dwell_arcs(one) + checks.rollers_apart(one)]
        codes[b] += group[0]  # the program's continuity
    touching = loc.in_contact.any(axis=0).reshape(B, N)
    FN = loc.guide.FN.reshape(B, N)
    add((touching & (FN < 0)).any(axis=1) | cand_any("FN_min", lambda v: v < 0), "jump")
    add((~touching).any(axis=1), "contact_lost")
    jam = (touching & forces.jammed(loc.guide).reshape(B, N)).any(axis=1)
    add(jam | cand_any("guide_jam", lambda v: v > 0), "guide_jam")
    if d0.dynamics.overhang_shrinks:  # Fig. 5: one program, so one peak, for the batch
        peak = checks.lift_peak_mm(d0)
        for b, d in enumerate(bt.designs):
            codes[b] += [v.code for v in checks.face_in_guide(SimpleNamespace(design=d), peak)]
    return [row + group[1] for row in codes]  # the elastic train's jump last


def _geometry_figures(bt: Batch) -> list[dict]:
    """Per design: the dwell radius (Eq. 20), psi (Eqs. 23, 25), the stations and the
    arcs the dwells subtend (Eqs. 24, 26), as report.summary lists them."""
    classic = bt.designs[0].motion.classic
    out = []
    for geo, st in zip(bt.geos, bt.stations, strict=True):
        arcs: dict[str, float | None] = {"high": None, "low": None}
        if classic is not None:
            arcs = {
                "high": classic.high_dwell_deg - 2 * geo.psi_h * R2D,
                "low": classic.low_dwell_deg + 2 * geo.psi_l * R2D,
            }
        out.append(
            {
                "dwell_radius_mm": geo.dwell_radius * 1e3,
                "psi_h_deg": geo.psi_h * R2D,
                "psi_l_deg": geo.psi_l * R2D,
                "stations_deg": [float(s) for s in st * R2D],
                "dwell_arc_deg": arcs,
            }
        )
    return out


SEGMENT_OF_PHI = "pressure_angle_max.segment"  # _refine's key: the candidates' segment kinds


def _phi_peak(grid: list[float | None], worst: dict, code: int) -> list[float | None]:
    """report._pressure_angle_max_deg per design: the grid's largest pressure angle
    [deg] on segments of kind ``code``, raised to the refined candidates' there."""
    cands = np.where(worst[SEGMENT_OF_PHI] == code, worst["pressure_angle_max"], np.nan)
    return _peak(grid, np.degrees(cands))


def _peak(grid: list[float | None], cands: np.ndarray) -> list[float | None]:
    """extremes.peak per design, for a maximum: the grid's value raised to the refined
    candidates' worst (``cands`` (B, C) from _refine)."""
    w = _worst(cands, 1.0)
    return [
        g if g is None or not np.isfinite(v) else float(max(g, v))
        for g, v in zip(grid, w, strict=True)
    ]


def _grid_figures(bt: Batch, loc, worst: dict) -> list[dict]:
    """Per design: the report's maxima and ranges over its grid (pressure angles,
    curvature radii, forces, stresses, the Hertz half-width, the flat face's width),
    the same masks as report.summary; the cycle's force and stress maxima between the
    samples too (``worst``: _refine's), as report.summary's."""
    B, N = bt.theta.shape
    F = bt.n_faces
    d0 = bt.designs[0]
    high = loc.prog.segment.reshape(B, N) == HIGH
    two = high & (loc.in_contact.sum(axis=0).reshape(B, N) == 2)
    code = np.array([g.code for g in bt.segs], dtype=np.int8)[loc.part].reshape(F, B, N)
    inc = loc.in_contact.reshape(F, B, N)
    rise, fall = inc & (code == RISE), inc & (code == FALL)
    phi = (np.abs(loc.pressure_angle) * R2D).reshape(F, B, N)
    rho = loc.rho.reshape(F, B, N)
    FN, Ft = loc.guide.FN.reshape(B, N), loc.Ft.reshape(B, N)
    stress = loc.stress.reshape(F, B, N)
    if d0.follower.radius_mm == 0.0:  # knife edge: no Hertz contact (contact.hertz_validity)
        b_half = np.full_like(stress, np.nan)
    else:
        w = d0.cam.width_mm * MM
        fn = np.where(inc, FN[None], 0.0)
        plain = hertz_line_stress(fn, bt.r[None, :, None], rho, w, compliance(d0))
        b_half = half_width(fn, plain, w)
    width: list[float | None] = [None] * B
    if bt.flat:  # report._flat_face_width_mm
        width = list(2.0 * np.abs(-loc.prog.V.reshape(B, N) - bt.stem_x[:, None]).max(axis=1) * 1e3)
    # report._face_contact_x_mm: a concave pad's or a flat face's stretch in contact
    x = (loc.point_world[..., 0].reshape(F, B, N) - bt.stem_x[None, :, None]) * 1e3
    spans = [
        _range(x[i], inc[i]) if bt.flat or d0.follower.kind.is_concave else [None] * B
        for i in range(F)
    ]
    faces = [{f"face{i + 1}": spans[i][b] if i < F else None for i in range(2)} for b in range(B)]
    cols = zip(
        _phi_peak(_max(phi, rise), worst, RISE),
        _phi_peak(_max(phi, fall), worst, FALL),
        _range(rho * 1e3, rise),
        _range(rho * 1e3, fall),
        _min(rho * 1e3, inc & (rho > 0) & np.isfinite(rho)),  # report._radii_mm
        _min(-rho * 1e3, inc & (rho < 0) & np.isfinite(rho)),
        _peak(_max(FN), worst["FN_max"]),
        _max(FN, high),
        _max(FN, two),
        _peak(_max(loc.guide.F1.reshape(B, N)), worst["F1_max"]),
        _peak(_max(loc.guide.F2.reshape(B, N)), worst["F2_max"]),
        _scaled(_peak(_max(stress), worst.get("stress_max", np.full((B, 1), np.nan))), 1e-6),
        _scaled(_max(np.where(high[None], stress, np.nan)), 1e-6),
        _scaled(_max(np.where(two[None], stress, np.nan)), 1e-6),
        _scaled(_max(b_half), 1e3),
        _max(Ft, high),
        width,
        faces,
        high.any(axis=1),
        strict=True,
    )
    return [
        {
            "pressure_angle_max_deg": {"rise": pa_r, "fall": pa_f},
            "curvature_radius_mm": {"rise": rho_r, "fall": rho_f},
            "radius_of_curvature_mm": {"convex_min": convex, "concave_min": concave},
            "contact_force_max_N": {
                "cycle": fn,
                "high_dwell": fn_h,
                "high_dwell_two_contact": fn_2,
            },
            "guide_force_max_N": {"F1": f1, "F2": f2},
            "contact_stress_max_MPa": {
                "cycle": s,
                "high_dwell": s_h if has_high else None,
                "high_dwell_two_contact": s_2,
            },
            "contact_half_width_max_mm": b,
            "contact_stress_allowable_MPa": allowable_contact_stress_MPa(d0),
            "contact_stress_safety_factor": d0.limits.contact_stress_safety_factor,
            "total_load_high_dwell_N": ft_h,
            "flat_face_width_min_mm": None if wid is None else float(wid),
            "face_contact_x_mm": face_x,
        }
        for (
            pa_r,
            pa_f,
            rho_r,
            rho_f,
            convex,
            concave,
            fn,
            fn_h,
            fn_2,
            f1,
            f2,
            s,
            s_h,
            s_2,
            b,
            ft_h,
            wid,
            face_x,
            has_high,
        ) in cols
    ]


# The report's keys a batched summary leaves out: the profile's figures and checks,
# what is computed along the profile (wear, its pitting life), and the variable-size
# descriptions (the dwell and station lists; their angles are in dwell_arc_deg and
# stations_deg), the sliding speed and the angles beyond Hertz' validity.
LEFT_OUT = (
    "profile",
    "verification",
    "wear_depth_max_um_per_Mcycle",
    "pitting_life_cycles",
    "pitting_life_hours",
    "sliding_speed_max_m_per_s",
    "hertz_beyond_validity_deg",
    "dwells",
    "stations",
)


# glibc's malloc hands every block over its mmap threshold (128 kB, raised only by a
# free of a larger mmapped one) fresh pages from the kernel, and returns them at free:
# a batch's temporaries, a few MB each, then fault in every page anew, each time.
# Heap blocks up to KEEP_MB, and up to that much freed memory kept for the next, made
# a --fast design ~7 % cheaper (64-design chunks, medians of five interleaved A/B runs:
# 3.29 against 3.53 ms).
KEEP_MB = 128
_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD = -1, -3  # (glibc's malloc.h)
_kept: list[bool] = []  # (whether keep_freed_memory ran in this process, and its answer)
KEEP_FREED = True  # False: leave malloc as it is (the app's server tunes it its own way)


def keep_freed_memory() -> bool:
    """Ask glibc's malloc, once per process, to serve blocks up to KEEP_MB from its heap
    and to keep up to KEEP_MB of freed memory for the next (mallopt); False where the C
    library is not glibc. The price: a process that ran a batch holds up to KEEP_MB it
    no longer uses (the batched core runs in the sweep's process or workers, and in the
    app's background worker; the app's server, which may run it when no worker starts,
    sets KEEP_FREED = False: it keeps its own small threshold, app.main._tune_malloc)."""
    if not KEEP_FREED:
        return False
    if not _kept:
        ok = False
        try:
            import ctypes
            import ctypes.util

            libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
            size = KEEP_MB << 20
            ok = bool(libc.mallopt(_M_MMAP_THRESHOLD, size))  # (each asked, whatever the
            ok = bool(libc.mallopt(_M_TRIM_THRESHOLD, size)) and ok  # other answers)
        except (OSError, AttributeError):  # not glibc (no mallopt): nothing to tune
            ok = False
        _kept.append(ok)
    return _kept[0]


def summaries(designs: list[Design]) -> list[dict]:
    """The report of each design (camcore.report.summary's keys but LEFT_OUT), plus
    ``violations`` as a list of {"code": ...} in the order of checks.run_all, ``valid``
    (no violation among the checks run) and ``profile_checked`` = False. The designs
    must make a batch (make_batch)."""
    keep_freed_memory()
    bt = make_batch(designs)
    B, N = bt.theta.shape
    loc = local(bt, bt.theta.ravel(), np.repeat(np.arange(B), N))
    on = _on_curve(loc, bt.segs)
    worst = _refine(bt, loc, on)
    trained, continuity, dynamic = _group_figures(bt)
    verdicts = _verdicts(bt, loc, on, worst, (continuity, dynamic))
    shaft = _shaft(bt, loc.torque.sum(axis=0).reshape(B, N), worst)
    springs = _springs(bt, loc.prog)
    lim = bt.designs[0].limits.min_jump_speed_ratio  # checks._jump_speed, run_all's last
    for row, spring in zip(verdicts, springs, strict=True):
        ratio = spring["jump_margin"]["jump_speed"]  # (None: it never jumps)
        if lim is not None and ratio is not None and ratio < checks.least(lim):
            row.append("jump_speed")
    parts = zip(
        bt.designs,
        verdicts,
        _geometry_figures(bt),
        _grid_figures(bt, loc, worst),
        springs,
        shaft,
        strict=True,
    )
    return [
        {
            "design": d.name,
            "follower": d.follower.kind.value,
            "valid": not codes,
            "profile_checked": False,
            "violations": [{"code": c} for c in codes],
            "unbounded": unbounded_of(codes, d.follower.kind),
            **geometry,
            **grid,
            **spring,
            "train": copy.deepcopy(trained),
            **machine_figures,
        }
        for d, codes, geometry, grid, spring, machine_figures in parts
    ]
