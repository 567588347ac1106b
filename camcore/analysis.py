"""One pass from a design to every result of the paper: the analysis pipeline.

design -> motion program -> face contacts and profile -> forces -> stress -> checks
(-> optional independent geometric verification). Everything is vectorized over
the cam-angle grid; the same code path serves all four followers.

``evaluate`` computes everything that is defined at a single cam angle, at any set of
angles; ``analyze`` runs it on the design's grid, assembles the profile, finds the
worst values of the checked quantities between the grid samples (camcore.extremes)
and lists the broken limits (camcore.checks).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from . import checks, extremes, forces, machine, motion, profile, sampling, train
from .contact import contact_stress
from .model import PAPER_FOLLOWERS, Design, FollowerKind
from .units import MM


@dataclass(frozen=True)
class Local:
    """Everything defined at one cam angle, over angles theta (N); per face (F, N).

    SI units throughout: metres, radians, newtons, pascals.
    """

    prog: motion.Program
    in_contact: np.ndarray  # (F, N) bool
    part: np.ndarray  # (F, N) index into the segments of the profile piece under the face
    point_world: np.ndarray  # (F, N, 2) contact point of each face in the world frame
    point_body: np.ndarray  # (F, N, 2) the same point in the cam frame (Eq. 11)
    normal: np.ndarray  # (F, N, 2) unit common normal (cam -> follower), world frame
    pressure_angle: np.ndarray  # (F, N) [rad], signed (see camcore.profile)
    kappa_pitch: np.ndarray  # (F, N) pitch-curve curvature [1/m]
    rho: np.ndarray  # (F, N) cam radius of curvature at the contact point [m] (Eq. 21)
    Ft: np.ndarray  # (N,) total load on the follower [N] (Eq. 29)
    guide: forces.GuideSolution  # F1, F2, F_N per contact, mode per angle
    FN: np.ndarray  # (F, N) contact force at each face [N], 0 where not touching
    stress: np.ndarray  # (F, N) Hertz stress [Pa] (Eq. 42)
    torque: np.ndarray  # (F, N) shaft torque [N m] each face's contact asks for


def _contact_slide(design: Design, geo: profile.Geometry, point_world, normal, prog):
    """mu_c sigma per face (F, N) for sliding faces with contact friction, else None
    (rollers roll; mu_c = 0 is the paper)."""
    mu = design.dynamics.contact_friction
    if mu == 0.0 or (geo.r > 0 and not geo.flat):
        return None
    return mu * np.sign(forces.tangential_slip(point_world, normal, prog.V))


@dataclass(frozen=True)
class Contacts:
    """Where each face touches the cam at angles theta (the geometry alone, Eqs. 1-19):
    what the profile sampling needs, without the forces."""

    prog: motion.Program
    faces: list[profile.FaceContact]  # per face: normal, world point, pressure angle
    in_contact: np.ndarray  # (F, N) bool
    part: np.ndarray  # (F, N) segment index of the profile piece under each face
    point_body: np.ndarray  # (F, N, 2) contact points in the cam frame (Eq. 11)


def contacts(
    design: Design,
    geo: profile.Geometry,
    segs: tuple[motion.Segment, ...],
    theta: np.ndarray,
    prog: motion.Program | None = None,
) -> Contacts:
    """The contact geometry (Eqs. 1-19) at the cam angles ``theta`` [rad]; ``prog``:
    the motion program there if the caller has it (``motion.program(design, theta)``)."""
    if prog is None:
        prog = motion.program(design, theta, segs)
    faces = [profile.face_contact(geo, f, prog) for f in geo.faces]
    windows, part = profile.contact_windows(geo, prog, segs)
    body = np.stack([profile.to_body(prog.theta, c.point) for c in faces])
    return Contacts(prog, faces, windows, part, body)


def evaluate(
    design: Design,
    geo: profile.Geometry,
    segs: tuple[motion.Segment, ...],
    theta: np.ndarray,
    prog: motion.Program | None = None,
) -> Local:
    """The per-angle results (Eqs. 1-19, 21, 29-42) at the cam angles ``theta`` [rad]
    (``prog`` as in ``contacts``)."""
    c = contacts(design, geo, segs, theta, prog)
    prog, windows, part, point_body = c.prog, c.in_contact, c.part, c.point_body
    normal = np.stack([f.normal for f in c.faces])
    point_world = np.stack([f.point for f in c.faces])
    kappa = np.stack([profile.pitch_curvature(geo, f, prog) for f in geo.faces])
    rho = np.stack(
        [profile.curvature_radius(geo, f, k) for f, k in zip(geo.faces, kappa, strict=True)]
    )
    Ft = forces.total_load(design, prog.S, prog.A)
    lever = np.stack([profile.lever_x(geo, f, prog) for f in geo.faces])
    r_arm = 0.0 if geo.flat else geo.r  # the guide arms are measured to the face centre
    slide = _contact_slide(design, geo, point_world, normal, prog)
    guide = forces.follower_forces(design, Ft, windows, normal, lever, r_arm, prog.S, prog.V, slide)
    FN = np.where(windows, guide.FN[None, :], 0.0)
    direction = normal if slide is None else forces.contact_direction(normal, slide)
    return Local(
        prog=prog,
        in_contact=windows,
        part=part,
        point_world=point_world,
        point_body=point_body,
        normal=normal,
        pressure_angle=np.stack([f.pressure_angle for f in c.faces]),
        kappa_pitch=kappa,
        rho=rho,
        Ft=Ft,
        guide=guide,
        FN=FN,
        stress=contact_stress(design, FN, rho),
        torque=forces.cam_torque(point_world, direction, FN),
    )


@dataclass(frozen=True, kw_only=True)
class Analysis(Local):
    """The per-angle results on the design's grid, the profile and the verdict."""

    design: Design
    geo: profile.Geometry
    segments: tuple[motion.Segment, ...]
    profile: profile.Polyline  # the cam as made: sampled to the export tolerance
    chord_error: float  # largest deviation of a profile chord from the exact cam [m]
    stations: np.ndarray  # cam angles of the stations [rad] (0-5 for the paper's program)
    worst: dict = field(default_factory=dict)  # camcore.extremes.worst_values
    violations: list[checks.Violation] = field(default_factory=list)
    lift_error: float | None = None  # max |lift - S| [m] of the geometric check
    train: train.Response | None = None  # elastic follower train (None: rigid)

    @property
    def theta(self) -> np.ndarray:
        return self.prog.theta

    @property
    def segment_code(self) -> np.ndarray:
        """(F, N) RISE / HIGH / FALL / LOW of the profile piece under each face."""
        return np.array([g.code for g in self.segments], dtype=np.int8)[self.part]

    @property
    def on_curve(self) -> np.ndarray:
        """(F, N) where a face touches a rise or fall curve (not a dwell arc)."""
        return extremes.on_curve(self, np.array([g.code for g in self.segments], dtype=np.int8))

    @property
    def n_contacts(self) -> np.ndarray:
        return self.in_contact.sum(axis=0)

    @property
    def valid(self) -> bool:
        return not self.violations

    def primary(self, per_face: np.ndarray) -> np.ndarray:
        """A per-face quantity at the face that touches (the rise face when both do)."""
        return np.where(self.in_contact[0], per_face[0], per_face[-1])

    @property
    def spring(self) -> machine.Spring:
        """machine.spring on this grid, searched once: the jump-speed check
        (limits.min_jump_speed_ratio) and the summary both read it. (Kept by hand, not
        a functools.cached_property: on Python 3.11 that holds one lock for every
        Analysis, and threads' searches would queue.)"""
        kept = vars(self).get("_spring")
        if kept is None:
            kept = vars(self)["_spring"] = machine.spring(self.design, self.theta, self.prog)
        return kept

    def local(self, theta: np.ndarray) -> Local:
        """The per-angle results at other cam angles (e.g. between the grid's)."""
        return evaluate(self.design, self.geo, self.segments, theta)


def stations(design: Design, geo: profile.Geometry) -> np.ndarray:
    """Cam angles of the stations [rad]: where a segment ends or the faces in contact
    change (one face -> two faces -> one face).

    For the paper's program these are its stations 0-5 (Sec. 4, Fig. 4; station 3 with
    the sign fixed), in the paper's numbering: 0: 0; 1: beta_r; 2: beta_r + 2 psi_h;
    3: beta_r + beta_h - 2 psi_h; 4: beta_r + beta_h; 5: beta_r + beta_h + beta_f.
    For any other program, every such angle in increasing order (``contact_changes``).
    """
    if design.motion.classic is not None:
        t1, t2, t3, _ = motion.boundaries_rad(design)
        return np.array([0.0, t1, t1 + 2 * geo.psi_h, t2 - 2 * geo.psi_h, t2, t3])
    return contact_changes(geo, motion.segments(design))


def contact_changes(geo: profile.Geometry, segs: tuple[motion.Segment, ...]) -> np.ndarray:
    """0, the segment boundaries and the angles where a face starts or stops touching
    (the ends of its windows, see profile.contact_windows), sorted in [0, 2 pi). A run
    of dwells (profile.dwell_runs) is one dwell: no station inside it; a face that
    passes from a curve onto an arc keeps touching: no station there unless a segment
    boundary is."""
    two_pi = 2 * np.pi
    runs = profile.dwell_runs(segs)
    # the boundaries, but those inside a run of dwells (one dwell: nothing begins there)
    cand = {0.0} | {
        g.start % two_pi for j, g in enumerate(segs) if g.is_motion or segs[j - 1].is_motion
    }
    if len(geo.faces) == 2:
        for i, side in enumerate(profile.face_sides(geo)):
            driven = motion.RISE if i == 0 else motion.FALL  # S1 drives rises, S2 falls
            spans = [(g.start, g.end) for g in segs if g.code == driven]
            for j, (t0, t1) in runs.items():
                start, end = profile.arc_span(geo, segs, j)
                psi_j = profile.dwell_psi(geo, segs[j].S0)
                lo, hi = max(t0, start - side * psi_j), min(t1, end - side * psi_j)
                if lo <= hi:
                    spans.append((lo, hi))
            for lo, hi in _merged_on_circle(spans):
                cand |= {lo % two_pi, hi % two_pi}
    out = sorted(t for t in cand if t < two_pi - 1e-12)  # (2 pi to round-off is 0)
    return np.array([t for i, t in enumerate(out) if i == 0 or t - out[i - 1] > 1e-12])


def _merged_on_circle(spans: list[tuple[float, float]], tol: float = 1e-12):
    """Closed intervals [lo, hi] [rad] on the circle, touching or overlapping ones
    merged (also across 2 pi); none if together they cover it."""
    two_pi = 2 * np.pi
    spans = sorted((lo % two_pi, lo % two_pi + hi - lo) for lo, hi in spans)
    out: list[list[float]] = []
    for lo, hi in spans:
        if out and lo <= out[-1][1] + tol:
            out[-1][1] = max(out[-1][1], hi)
        else:
            out.append([lo, hi])
    while len(out) > 1 and out[-1][1] >= out[0][0] + two_pi - tol:  # across 2 pi
        last = out.pop()
        out[0] = [last[0], max(last[1], out[0][1] + two_pi)]
    if out and out[0][1] - out[0][0] >= two_pi - tol:
        return []
    return [tuple(x) for x in out]


def analyze(design: Design, verify: bool = True, theta: np.ndarray | None = None) -> Analysis:
    """Run the paper's whole method on ``design``.

    Parameters
    ----------
    design : the design (validated pydantic model).
    verify : also run the independent geometric check (camcore.verify).
    theta : cam angles [rad]; default: the design's grid (0 .. 2 pi at its resolution,
        with every segment boundary and station on the grid, and every rise and fall
        resolved by motion.MIN_MOTION_STEPS samples at least).
    """
    geo = profile.geometry(design)
    st = stations(design, geo)
    th = motion.theta_grid(design, tuple(st)) if theta is None else np.asarray(theta, float)
    return _analyze(design, geo, st, th, verify)


def _sampled(loc, design, geo, segs, st, th, tol: float) -> sampling.Sampled:
    """The profile of the evaluated grid ``loc`` sampled to the chordal tolerance
    ``tol`` [m], each segment boundary and station (``st``) a vertex."""
    breaks = np.mod([*(g.start for g in segs), *st], 2 * np.pi)
    cuts = np.unique(np.clip(np.searchsorted(th, breaks), 0, th.size - 1))
    return sampling.sample_profile(
        loc, geo, segs, lambda x: contacts(design, geo, segs, x), np.union1d(cuts, [0]), tol
    )


def profile_at(a: Analysis, tol: float) -> Analysis:
    """``a`` with its profile sampled to the chordal tolerance ``tol`` [m] instead of
    the design's: a cutter path needs a finer one where offsetting stretches the
    chords (camcore.toolpath). Everything else is ``a``'s."""
    made = _sampled(a, a.design, a.geo, a.segments, a.stations, a.theta, tol)
    return replace(a, profile=made.polyline, chord_error=made.chord_error)


def _analyze(
    design: Design,
    geo: profile.Geometry,
    st: np.ndarray,
    th: np.ndarray,
    verify: bool,
    prog: motion.Program | None = None,
) -> Analysis:
    """analyze on the grid ``th`` with the stations ``st`` [rad]; ``prog``: the motion
    program on ``th`` if the caller has it (compare shares one between followers)."""
    segs = motion.segments(design)
    loc = evaluate(design, geo, segs, th, prog)
    made = _sampled(loc, design, geo, segs, st, th, design.limits.export_tolerance_mm * MM)
    result = Analysis(
        **vars(loc),
        design=design,
        geo=geo,
        segments=segs,
        profile=made.polyline,
        chord_error=made.chord_error,
        stations=st,
    )
    result = replace(result, worst=extremes.worst_values(result), train=train.respond(design))
    lift_error = None
    if verify:
        from .verify import max_lift_error

        lift_error = max_lift_error(result)
    violations = checks.run_all(result, lift_error)
    done = replace(result, violations=violations, lift_error=lift_error)
    if "_spring" in vars(result):  # the check's spring search, kept for the summary
        vars(done)["_spring"] = vars(result)["_spring"]
    return done


def compare(
    design: Design,
    verify: bool = False,
    kinds: tuple[FollowerKind, ...] = PAPER_FOLLOWERS,
    errors: bool = False,
) -> dict[FollowerKind, Analysis | str]:
    """The same design with each follower in ``kinds`` (default: the paper's four,
    Table 1, Figs. 11-13). ``errors``: a follower for which the design is not valid
    input (e.g. a face radius a roller cannot take) gets the reason as a string instead
    of raising.

    The followers share one grid and one evaluation of the motion program (issue 12):
    the design's grid with every follower's stations on it, so each curve is compared
    at the same angles and each follower's contact changes are sampled exactly. A
    follower's numbers differ from its own ``analyze`` only by where the grid samples
    fall (its grid has fewer stations; the worst values between samples agree).
    """
    from pydantic import ValidationError

    from .model import format_validation_error

    out: dict[FollowerKind, Analysis | str] = {}
    made: dict[FollowerKind, tuple[Design, profile.Geometry, np.ndarray]] = {}
    for k in kinds:
        try:
            d = design.with_kind(k)
        except ValidationError as exc:
            if not errors:
                raise
            out[k] = format_validation_error(exc)
            continue
        geo = profile.geometry(d)
        made[k] = (d, geo, stations(d, geo))
    if made:
        every = np.concatenate([st for _, _, st in made.values()])
        grid = motion.theta_grid(design, tuple(np.unique(every)))
        prog = motion.program(design, grid)
        for k, (d, geo, st) in made.items():
            out[k] = _analyze(d, geo, st, grid, verify, prog)
    return {k: out[k] for k in kinds}
