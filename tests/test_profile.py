"""Profile synthesis against the paper's own equations, closed forms, and geometry."""

import dataclasses
import math

import numpy as np
import pytest

from camcore import checks, profile
from camcore.analysis import analyze
from camcore.model import Design, FollowerKind, load_preset
from camcore.motion import FALL, RISE, program, theta_grid
from camcore.verify import follower_lift

PAPER = load_preset("paper_example")
KINDS = list(FollowerKind)


def paper_eq12_eq19(theta, S, V, rf, rb, e):
    """Eqs. 3, 5, 12 (rise, face S1) and 13, 19 (fall, face S2), transcribed as printed."""
    L = math.sqrt((rf + rb) ** 2 - e**2) - S  # Eq. 3
    phi_r = np.arctan((V + e) / L)  # Eq. 5
    xr = L * np.sin(theta) + e * np.cos(theta) + rf * np.sin(phi_r + theta)  # Eq. 12
    yr = -L * np.cos(theta) + e * np.sin(theta) - rf * np.cos(phi_r + theta)
    phi_f = np.arctan((e - V) / L)  # Eq. 13
    xf = L * np.sin(theta) - e * np.cos(theta) - rf * np.sin(phi_f - theta)  # Eq. 19
    yf = -L * np.cos(theta) - e * np.sin(theta) - rf * np.cos(phi_f - theta)
    return np.stack([xr, yr], -1), np.stack([xf, yf], -1), phi_r, phi_f


def test_double_concave_reproduces_eqs_12_and_19():
    a = analyze(PAPER, verify=False)
    p = a.prog
    rise, fall, phi_r, phi_f = paper_eq12_eq19(p.theta, p.S, p.V, -0.250, 0.080, 0.010)
    r, f = p.segment == RISE, p.segment == FALL
    np.testing.assert_allclose(a.point_body[0][r], rise[r], atol=1e-13)
    np.testing.assert_allclose(a.point_body[1][f], fall[f], atol=1e-13)
    # pressure angle: Eq. 5 on the rise; the fall is reported with the textbook sign (-Eq. 13)
    np.testing.assert_allclose(a.pressure_angle[0][r], phi_r[r], atol=1e-13)
    np.testing.assert_allclose(a.pressure_angle[1][f], -phi_f[f], atol=1e-13)


def test_dwell_radius_eq20_and_psi_eqs23_25():
    rf, rb, e, h = -250.0, 80.0, 10.0, 15.0
    R = abs(rf) - math.sqrt((rf + rb) ** 2 - 2 * h * math.sqrt((rf + rb) ** 2 - e**2) + h**2)
    g = profile.geometry(PAPER)
    assert g.dwell_radius * 1e3 == pytest.approx(R, rel=1e-12)
    assert g.psi_h == pytest.approx(math.asin(e / (-R - rf)), rel=1e-12)  # Eq. 23
    assert g.psi_l == pytest.approx(math.asin(e / (-rf - rb)), rel=1e-12)  # Eq. 25
    # the synthesized high-dwell arc has radius R, the low-dwell arc r_b
    a = analyze(PAPER, verify=False)
    radius = np.hypot(*a.profile.points.T) * 1e3
    assert radius.max() == pytest.approx(R, abs=1e-9)
    assert radius.min() == pytest.approx(rb, abs=1e-9)


def test_roller_dwell_radius_is_pitch_minus_roller():
    """Single roller, e = 0: R = r_b + h (the pitch circle grows by h)."""
    d = PAPER.with_kind(FollowerKind.single_roller)
    assert profile.geometry(d).dwell_radius == pytest.approx(0.095, abs=1e-15)


def grid_polyline(a):
    """The profile through the contact points of the analysis grid itself."""
    return profile.assemble(a.prog, a.segments, a.point_body, a.in_contact, a.part, a.geo)


@pytest.mark.parametrize("kind", KINDS)
def test_geometric_check_on_paper_example(kind):
    """The exported profile (1 um chords) gives S(theta) within its chord error, at the
    grid angles and between them; through the grid's own contact points the check is
    exact to round-off at those angles."""
    a = analyze(PAPER.with_kind(kind))
    assert a.valid, [v.message for v in a.violations]
    assert 1e-8 < a.chord_error <= 1e-6  # metres
    assert a.lift_error <= checks.lift_tolerance(a) < 1.1e-6
    faces = [(f.r, f.x_c) for f in a.geo.faces]
    lift = follower_lift(grid_polyline(a).points, a.theta, faces, a.geo.r_b)
    assert np.max(np.abs(lift - a.prog.S)) < 1e-12


@pytest.mark.parametrize("kind", [FollowerKind.double_concave, FollowerKind.double_roller])
def test_geometric_check_catches_swapped_faces(monkeypatch, kind):
    original = profile.geometry

    def swapped(design):
        g = original(design)
        return dataclasses.replace(g, faces=g.faces[::-1])

    monkeypatch.setattr(profile, "geometry", swapped)
    a = analyze(PAPER.with_kind(kind))
    assert a.lift_error > 1e-4  # metres: a tenth of a millimetre or more
    assert "geometric_check" in [v.code for v in a.violations]


def test_geometric_check_catches_wrong_rotation_sense():
    """A cam synthesized for counter-clockwise rotation fails when run clockwise."""
    a = analyze(PAPER.with_kind(FollowerKind.single_roller), verify=False)
    mirrored = a.profile.points * np.array([-1.0, 1.0])
    faces = [(f.r, f.x_c) for f in a.geo.faces]
    lift = follower_lift(mirrored[::-1], a.theta, faces, a.geo.r_b)
    assert np.max(np.abs(lift - a.prog.S)) > 1e-3


@pytest.mark.parametrize("kind", [FollowerKind.double_concave, FollowerKind.double_roller])
def test_stations_from_geometry(kind):
    """Which faces touch, found by lowering each face alone onto the finished cam,
    agrees with the synthesized contact windows - and with station 3 at
    beta_r + beta_h - 2 psi_h (the paper prints + 2 psi_h, which puts it after station 4)."""
    a = analyze(PAPER.with_kind(kind), verify=False)
    pts = grid_polyline(a).points
    per_face = [follower_lift(pts, a.theta, [(f.r, f.x_c)], a.geo.r_b) for f in a.geo.faces]
    touching = np.stack([np.abs(lf - a.prog.S) < 1e-13 for lf in per_face])
    np.testing.assert_array_equal(touching, a.in_contact)
    deg = np.degrees(a.stations)
    psi_h = math.degrees(a.geo.psi_h)
    np.testing.assert_allclose(deg, [0, 100, 100 + 2 * psi_h, 170 - 2 * psi_h, 170, 300])
    assert np.all(np.diff(deg) > 0)
    both = a.theta[touching.all(0) & (a.prog.segment == 1)]
    assert math.degrees(both.min()) == pytest.approx(deg[2], abs=0.1)
    assert math.degrees(both.max()) == pytest.approx(deg[3], abs=0.1)


def eq21_exact(g, face, p):
    """Eq. 21 evaluated on the traced profile p(theta) = R(theta) A(theta), with exact
    derivatives (the jerk enters through A''): the reference the parallel-curve formula
    of camcore.profile is checked against where the profile does not fold back."""
    V, Ac, Jk = p.V, p.A, p.J
    yc = g.y0 + p.S
    u = np.stack([face.x_c + V, yc], -1)
    du = np.stack([Ac, V], -1)
    ddu = np.stack([Jk, Ac], -1)
    m = np.hypot(u[:, 0], u[:, 1])[:, None]
    udu = np.sum(u * du, -1, keepdims=True)
    dm = udu / m
    ddm = (np.sum(du * du, -1, keepdims=True) + np.sum(u * ddu, -1, keepdims=True)) / m - (
        udu**2 / m**3
    )
    s = g.sigma
    n = s * u / m
    dn = s * (du / m - u * dm / m**2)
    ddn = s * (ddu / m - 2 * du * dm / m**2 - u * ddm / m**2 + 2 * u * dm**2 / m**3)
    zero = np.zeros_like(V)
    if math.isinf(face.r):  # flat face: the contact (-V, Y) in the world frame
        A, dA, ddA = (np.stack(c, -1) for c in ((-V, yc), (-Ac, V), (-Jk, Ac)))
    else:
        A = np.stack([face.x_c + zero, yc], -1) - face.r * n
        dA = np.stack([zero, V], -1) - face.r * dn
        ddA = np.stack([zero, Ac], -1) - face.r * ddn
    rot = np.array([[0.0, -1.0], [1.0, 0.0]])
    p1 = A @ rot.T + dA
    p2 = -A + 2 * dA @ rot.T + ddA
    cross = p1[:, 0] * p2[:, 1] - p1[:, 1] * p2[:, 0]
    return np.hypot(p1[:, 0], p1[:, 1]) ** 3 / cross


def rho_of(g, face, p):
    return profile.curvature_radius(g, face, profile.pitch_curvature(g, face, p))


@pytest.mark.parametrize("kind", KINDS)
def test_curvature_matches_finite_differences(kind):
    """rho (parallel-curve formula) agrees with Eq. 21 by finite differences of the
    traced contact points."""
    d = PAPER.with_kind(kind)
    g = profile.geometry(d)
    th = np.radians(np.linspace(5, 95, 901))
    p = program(d, th)
    for face in g.faces[:1]:
        rho = rho_of(g, face, p)
        hstep = 1e-5
        pts = []
        for k in (-1, 0, 1):
            t = th + k * hstep
            pts.append(profile.to_body(t, profile.face_contact(g, face, program(d, t)).point))
        d1 = (pts[2] - pts[0]) / (2 * hstep)
        d2 = (pts[2] - 2 * pts[1] + pts[0]) / hstep**2
        rho_fd = np.hypot(*d1.T) ** 3 / (d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])
        np.testing.assert_allclose(rho, rho_fd, rtol=1e-4)


@pytest.mark.parametrize("kind", KINDS)
def test_curvature_parallel_curve_equals_eq21_exact(kind):
    """rho = sigma / kappa_pitch - r (S, V, A only) equals Eq. 21 evaluated with exact
    derivatives of the traced profile (which needs the jerk) wherever the profile does
    not fold back: an independent check of both."""
    d = PAPER.with_kind(kind)
    g = profile.geometry(d)
    p = program(d, theta_grid(d))
    for face in g.faces:
        np.testing.assert_allclose(
            rho_of(g, face, p), eq21_exact(g, face, p), rtol=1e-9, atol=1e-12
        )


FOLDED = Design.model_validate(
    {
        **PAPER.model_dump(),
        "follower": {**PAPER.follower.model_dump(), "kind": "single_concave"},
        "motion": {**PAPER.motion.model_dump(), "lift_mm": 12.0, "rise_deg": 40.0},
    }
)


def test_folded_concave_profile_is_not_convex():
    """Issue 8: where the pitch radius passes |r_f| the profile folds back. Eq. 21 on the
    traced curve comes out positive there (the curve turns round), so Eq. 22 never fired;
    the parallel-curve rho is negative and the check reports curvature_convex."""
    a = analyze(FOLDED, verify=False)
    g, face = a.geo, a.geo.faces[0]
    folded = a.on_curve[0] & (a.kappa_pitch[0] > 0) & (a.kappa_pitch[0] < -1 / g.r)
    assert folded.sum() > 10
    traced = eq21_exact(g, face, a.prog)[folded]
    assert np.all(traced > 0)  # the old, wrong sign
    assert np.all(a.rho[0, folded] < 0)
    codes = {v.code: v for v in a.violations}
    assert "curvature_convex" in codes and "curvature_face" not in codes
    lo, hi = codes["curvature_convex"].ranges_deg[0]
    assert 0 < lo < hi < 40
    # and the Hertz stress is not computed from a spurious small positive rho there
    assert np.all(a.stress[0, folded] == 0)


def test_roller_may_run_on_a_concave_flank():
    """A roller on a concave flank (rho < -r_c) is fine: only a pitch radius in
    (0, r_c] undercuts."""
    d = Design.model_validate(
        {
            "motion": {"lift_mm": 40, "rise_deg": 60, "high_dwell_deg": 60, "fall_deg": 60},
            "follower": {"kind": "single_roller", "roller_radius_mm": 8},
            "cam": {"base_radius_mm": 30},
        }
    )
    a = analyze(d)
    assert (a.on_curve[0] & (a.rho[0] < -a.geo.r)).sum() > 10  # concave flanks exist
    assert a.lift_error <= checks.lift_tolerance(a)
    assert "roller_undercut" not in {v.code for v in a.violations}
    assert "curvature_convex" not in {v.code for v in a.violations}
    # a roller larger than the tightest convex pitch radius undercuts: the rule fires,
    # and the independent geometric check confirms the cam no longer gives S(theta)
    big = d.model_copy(
        update={"follower": d.follower.model_copy(update={"roller_radius_mm": 40.0})}
    )
    b = analyze(big)
    assert 1.0 / b.kappa_pitch[b.on_curve].max() < b.geo.r  # pitch radius below r_c
    assert {"roller_undercut", "geometric_check"} <= {v.code for v in b.violations}


def test_dwell_curvature_is_arc_radius():
    a = analyze(PAPER, verify=False)
    high = a.in_contact & (a.segment_code == 1)
    low = a.in_contact & (a.segment_code == 3)
    np.testing.assert_allclose(a.rho[high], a.geo.dwell_radius, rtol=1e-9)
    np.testing.assert_allclose(a.rho[low], 0.080, rtol=1e-9)


def test_profile_area_and_star_shape():
    for kind in KINDS:
        a = analyze(PAPER.with_kind(kind), verify=False)
        assert a.profile.is_star_shaped()
        # the cam lies between the base circle and the dwell circle
        assert math.pi * 0.080**2 < a.profile.area < math.pi * a.geo.dwell_radius**2


def test_offset_too_large_is_rejected():
    from pydantic import ValidationError

    data = PAPER.model_dump()
    data["follower"]["offset_mm"] = 171.0  # |r_f + r_b| = 170
    with pytest.raises(ValidationError, match="offset_mm"):
        Design.model_validate(data)


@pytest.mark.parametrize("kind", KINDS)
def test_normal_and_curvature_from_the_finished_polyline(kind):
    """From the finished profile alone: the normal at each rise/fall contact vertex
    (perpendicular to the chord through its neighbours, turned to the world frame) is
    the instant-centre normal of Eqs. 5/13, and the circle through three consecutive
    vertices has the radius of Eq. 21."""
    a = analyze(PAPER.with_kind(kind), verify=False)
    P, part, th = a.profile.points, a.profile.part, a.profile.theta
    k = np.flatnonzero((part == RISE) | (part == FALL))
    k = k[(k > 0) & (k < len(P) - 1)]
    k = k[(part[k - 1] == part[k]) & (part[k + 1] == part[k])][::7]
    prev, here, nxt = P[k - 1], P[k], P[k + 1]
    chord = nxt - prev
    outward = np.stack([chord[:, 1], -chord[:, 0]], -1)  # CCW profile: right of travel
    outward /= np.hypot(*outward.T)[:, None]
    c, s = np.cos(th[k]), np.sin(th[k])
    world = np.stack(
        [c * outward[:, 0] + s * outward[:, 1], -s * outward[:, 0] + c * outward[:, 1]], -1
    )
    # which face touched at that angle, and its normal there (the profile's angles are
    # not the grid's: evaluate the closed forms at them)
    loc = a.local(th[k])
    at = np.arange(k.size)
    face = np.where(part[k] == RISE, 0, len(a.geo.faces) - 1)
    np.testing.assert_allclose(world, loc.normal[face, at], atol=2e-5)
    # Menger curvature: 4 * area / (product of the three side lengths)
    u, v = here - prev, nxt - here
    cross = u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]
    rho_fit = (np.hypot(*u.T) * np.hypot(*v.T) * np.hypot(*chord.T)) / (2 * cross)
    np.testing.assert_allclose(rho_fit, loc.rho[face, at], rtol=2e-3)


@pytest.mark.parametrize("kind", KINDS)
def test_dwell_arcs_subtend_eqs_24_and_26(kind):
    """The arcs of the finished profile, measured as polar-angle spans of its vertices,
    subtend beta_h - 2 psi_h (Eq. 24) and beta_l + 2 psi_l (Eq. 26)."""
    from camcore.report import summary

    a = analyze(PAPER.with_kind(kind), verify=False)
    s = summary(a)
    P, part = a.profile.points, a.profile.part
    for seg, key in ((1, "high"), (3, "low")):
        idx = np.flatnonzero(part == seg)
        # include the neighbouring motion-curve vertices where the arc begins and ends
        ends = P[[idx[0] - 1, (idx[-1] + 1) % len(P)]]
        span = np.degrees(
            np.mod(
                np.arctan2(ends[1, 1], ends[1, 0]) - np.arctan2(ends[0, 1], ends[0, 0]), 2 * math.pi
            )
        )
        assert span == pytest.approx(s["dwell_arc_deg"][key], abs=1e-6)


@pytest.mark.parametrize("kind", [FollowerKind.double_concave, FollowerKind.double_roller])
@pytest.mark.parametrize("e", [0.0, -0.0])
def test_double_follower_with_zero_offset_is_one_face(kind, e):
    """Issue 8: e = 0 was rejected as "crosses itself". Its two faces coincide: a valid,
    degenerate design, analysed as one face on the centreline, like the single kind."""
    d = PAPER.with_kind(kind).model_copy(deep=True)
    d = Design.model_validate(
        {**d.model_dump(), "follower": {**d.follower.model_dump(), "offset_mm": e}}
    )
    assert math.copysign(1.0, d.follower.offset_mm) == 1.0  # -0.0 is stored as 0.0
    a = analyze(d)
    single = analyze(
        PAPER.with_kind(
            "single_concave" if kind == FollowerKind.double_concave else "single_roller"
        )
    )
    assert a.valid, [v.message for v in a.violations]
    assert len(a.geo.faces) == 1 and a.geo.psi_h == 0.0
    np.testing.assert_array_equal(a.profile.points, single.profile.points)
    np.testing.assert_array_equal(a.guide.FN, single.guide.FN)


@pytest.mark.parametrize("kind", KINDS)
def test_coarse_resolution_export_is_within_tolerance(kind):
    """At 5 deg analysis resolution the exported profile was 0.114 mm off the exact cam
    between grid angles. Now it is sampled to the export tolerance whatever the grid:
    an independent dense check (0.01 deg, exact contact points from the closed forms)
    finds every exact contact point within the tolerance of the polyline."""
    data = PAPER.with_kind(kind).model_dump()
    data["limits"]["resolution_deg"] = 5.0
    a = analyze(Design.model_validate(data))
    assert a.valid, [v.message for v in a.violations]
    tol = a.design.limits.export_tolerance_mm * 1e-3
    assert a.chord_error <= tol
    assert a.lift_error <= checks.lift_tolerance(a)
    th = np.linspace(0, 2 * math.pi, 36000, endpoint=False)
    loc = a.local(th)
    P = a.profile.points
    Q = np.roll(P, -1, axis=0)
    for f in range(loc.in_contact.shape[0]):
        X = loc.point_body[f][loc.in_contact[f]]
        # distance from each exact point to the nearest chord (polar neighbourhood)
        ang = np.arctan2(P[:, 1], P[:, 0])
        order = np.argsort(ang)
        k = order[np.searchsorted(ang[order], np.arctan2(X[:, 1], X[:, 0])) % len(P)]
        best = np.full(X.shape[0], np.inf)
        for shift in range(-3, 3):
            i = (k + shift) % len(P)
            d = Q[i] - P[i]
            t = np.clip(np.einsum("ij,ij->i", X - P[i], d) / np.einsum("ij,ij->i", d, d), 0, 1)
            best = np.minimum(best, np.hypot(*(P[i] + t[:, None] * d - X).T))
        assert best.max() <= tol * 1.001, best.max()


def _nearest_chord(P: np.ndarray, X: np.ndarray) -> np.ndarray:
    """Distance [m] of each point X to the closed polyline P (all chords, brute force)."""
    Q = np.roll(P, -1, axis=0)
    d = Q - P
    t = np.clip(np.einsum("mij,ij->mi", X[:, None, :] - P[None], d) / (d * d).sum(1), 0, 1)
    foot = P[None] + t[..., None] * d[None]
    return np.hypot(*(foot - X[:, None, :]).transpose(2, 0, 1)).min(axis=1)


@pytest.mark.parametrize("kind", ["double_roller", "double_concave"])
def test_zero_low_dwell_keeps_its_arc(kind):
    """With no low dwell (fall straight into rise) a double follower's cam still carries
    the low-dwell arc of 2 psi_l (Eq. 26, beta_l = 0) between the fall face's last and the
    rise face's first contact. It used to be left out: the exported cam had a chord with
    a 2.5 mm sagitta there, and the chord from the fall to the rise was never measured.
    Exact points on that arc (radius r_b) must lie on the polyline within tolerance."""
    d = Design.model_validate(
        {
            "motion": {"lift_mm": 1, "rise_deg": 120, "high_dwell_deg": 120, "fall_deg": 120},
            "follower": {
                "kind": kind,
                "roller_radius_mm": 1,
                "face_radius_mm": -100,
                "offset_mm": 9.5,
            },
            "cam": {"base_radius_mm": 18},
        }
    )
    a = analyze(d)
    assert a.lift_error <= checks.lift_tolerance(a)
    psi_l = a.geo.psi_l
    assert math.degrees(psi_l) > 5  # a wide arc: the bug's chord is 0.1 mm or more off
    # the contact at theta = 0 of the rise face is at polar pi/2 + psi_l (S1 left of the
    # stem), the fall face's last contact at pi/2 - psi_l; the arc is between them
    ang = np.linspace(math.pi / 2 - psi_l, math.pi / 2 + psi_l, 200)
    X = a.geo.r_b * np.column_stack([np.cos(ang), np.sin(ang)])
    tol = d.limits.export_tolerance_mm * 1e-3
    assert _nearest_chord(a.profile.points, X).max() <= tol * 1.001


def test_invalid_profile_costs_a_bounded_check(monkeypatch):
    """A profile that crosses itself (faces swapped) asks the sampler for millions of
    vertices and the unpruned check for O(N M): both are bounded."""
    from camcore import sampling

    original = profile.geometry
    monkeypatch.setattr(
        profile,
        "geometry",
        lambda d: dataclasses.replace(original(d), faces=original(d).faces[::-1]),
    )
    a = analyze(PAPER.with_kind(FollowerKind.double_roller))
    assert a.profile.points.shape[0] <= 2 * sampling.MAX_VERTICES
    assert {"profile_crossing", "geometric_check", "export_tolerance"} <= {
        v.code for v in a.violations
    }


def test_range_maxima_of_the_sparse_table():
    """verify._range_max (the radius that tightens a wedge) against the brute force."""
    from camcore.verify import _range_max, sparse_table

    rng = np.random.default_rng(5)
    x = rng.random(301)
    table = sparse_table(x)
    s0 = rng.integers(0, 300, 500)
    e0 = s0 + rng.integers(1, 302 - s0)
    want = [x[a:b].max() for a, b in zip(s0, e0, strict=True)]
    np.testing.assert_array_equal(_range_max(table, s0, e0), want)


def test_a_rollers_wedge_holds_every_point_that_can_beat_the_bound():
    """verify._wedge for rollers: every point of the box a vertex or chord must lie in to
    beat the bound L (|X - x_c| <= r, Y >= L - r, within rho_max of the axis) is inside
    the wedge of directions; a double roller's face off the stem looks on its own side
    only (a symmetric wedge about straight up ran twice the vertices)."""
    from camcore.verify import _wedge

    rng = np.random.default_rng(11)
    for _ in range(200):
        r, x_c = rng.uniform(0.0, 0.02), rng.uniform(-0.04, 0.04)
        rho_max = rng.uniform(0.05, 0.1)
        L = np.array([rng.uniform(r + 1e-3, rho_max + r)])
        ctr, hw = _wedge(L, r, x_c, rho_max)
        X = x_c + rng.uniform(-r, r, 400)
        Y = rng.uniform(L[0] - r, rho_max, 400)
        inside = np.hypot(X, Y) <= rho_max
        off = np.angle(np.exp(1j * (np.arctan2(Y, X) - ctr[0])))  # wrapped to (-pi, pi]
        assert hw[0] < np.pi and (np.abs(off[inside]) <= hw[0]).all()
    ctr, hw = _wedge(np.array([0.07]), 0.008, -0.010, 0.075)  # the paper's left roller
    assert ctr[0] - hw[0] > np.pi / 2 and hw[0] < np.radians(8)


def _random_star(rng) -> np.ndarray:
    """A closed, counter-clockwise profile star-shaped about the axis [m]: a wavy
    radius with noise at sorted polar angles (the pruned check applies to it)."""
    phi = np.unique(rng.uniform(-np.pi, np.pi, int(rng.integers(8, 600))))
    base = rng.uniform(0.02, 0.1)
    wave = base * rng.uniform(0.0, 0.6) * rng.uniform(0.2, 1.0)
    rad = base + wave * np.sin(int(rng.integers(1, 6)) * phi + rng.uniform(0, 6))
    rad = np.maximum(rad + rng.normal(scale=base * 0.01 * rng.random(), size=phi.size), base / 10)
    return np.column_stack([rad * np.cos(phi), rad * np.sin(phi)])


def _random_faces(rng) -> list[tuple[float, float]]:
    """One face or a symmetric pair: a roller (some narrower than the vertex spacing,
    some knife edges), a concave face of any width, or a flat face."""
    kind = int(rng.integers(0, 4))
    r = {
        0: rng.uniform(0.0, 0.03) if rng.random() < 0.9 else 0.0,
        1: -rng.uniform(0.005, 0.5),
        2: np.inf,
        3: rng.uniform(0.0005, 0.002),
    }[kind]
    if rng.random() < 0.5:
        e = rng.uniform(0.0, 0.05)
        return [(r, -e), (r, e)]
    return [(r, 0.0 if np.isinf(r) else rng.uniform(-0.04, 0.04))]


def test_the_pruned_check_equals_the_brute_force_on_random_profiles():
    """verify.follower_lift's pruning (wedges, per-angle runs, one bound for both faces)
    on random star-shaped profiles and followers, bit for bit against the plain
    maximum: a wedge that missed a vertex, e.g. a roller's without its box's upper
    corners, fails here (tried)."""
    from camcore.verify import follower_lift

    rng = np.random.default_rng(2026)
    tried = 0
    while tried < 150:
        pts, faces = _random_star(rng), _random_faces(rng)
        r, x_c = faces[0]
        r_b = 0.9 * float(np.hypot(*pts.T).min())
        if not np.isinf(r) and (r + r_b <= 0 or (r + r_b) ** 2 < x_c**2):
            continue  # (no rest position on the base circle)
        th = np.sort(rng.uniform(0.0, 2 * np.pi, int(rng.integers(5, 400))))
        args = (pts, th, faces, r_b)
        np.testing.assert_array_equal(follower_lift(*args), follower_lift(*args, prune=False))
        tried += 1


def test_the_pruned_check_keeps_a_long_chord_and_any_cam_angle():
    """Two cases a review built, pruned against the brute force: (1) a knife edge's
    chord whose end lies a hair (7e-11 m) beside the other face, where _face_max's
    round-off room on a chord's parameter reaches past the wedge of a chord longer than
    its end's radius; (2) cam angles of 1e9 rad, where a 2 pi wrap in floating point
    had moved the wedges by more than their slack (cos and sin reduce exactly)."""
    from camcore.verify import follower_lift

    e = -0.005
    pts = np.array(
        [(0, 0.05), (-0.001, 0.2), *[(-0.0015 - 0.0005 * i, 0.045) for i in range(5)]]
        + [(-0.004, 0.049), (e - 7e-11, 0.05 + 1e-11), (-0.2, 0.05), (-0.2, -0.1)]
        + [(0, -0.1), (0.1, -0.05), (0.05, 0.02)]
    )
    args = (pts, [0.0], [(0.0, 0.0), (0.0, e)], 1.0)
    np.testing.assert_array_equal(follower_lift(*args), follower_lift(*args, prune=False))
    turn = 1e9
    body = math.atan2(math.sin(turn), math.cos(turn))  # what the world's 0 is at theta
    d = np.arange(-20, 21) * 1e-8  # vertices 1e-8 rad apart round straight up, a peak
    rad = np.concatenate([0.05 - 1e-3 * np.abs(d + 0.5e-8) / 1e-7, np.full(12, 0.04)])
    world = np.concatenate([np.pi / 2 + d, np.linspace(np.pi / 2 + 0.5, np.pi * 2.5 - 0.5, 12)])
    phi = world + body
    pts = np.column_stack([rad * np.cos(phi), rad * np.sin(phi)])[np.argsort(phi % (2 * np.pi))]
    args = (pts, np.array([turn, turn + 1e-3, 0.3]), [(0.0, 1e-3), (0.0, 0.0)], 1.0)
    np.testing.assert_array_equal(follower_lift(*args), follower_lift(*args, prune=False))


def test_tightened_check_equals_the_brute_force_on_every_paper_follower():
    """The pruned check with tightened wedges gives the plain maximum bit for bit."""
    from camcore.verify import follower_lift

    for kind in FollowerKind:
        a = analyze(PAPER.with_kind(kind), verify=False)
        th = a.theta[::37]
        args = (a.profile.points, th, [(f.r, f.x_c) for f in a.geo.faces], a.geo.r_b)
        np.testing.assert_array_equal(follower_lift(*args), follower_lift(*args, prune=False))


def test_a_vanishing_offset_is_no_offset():
    """A double follower's offset of 1e-313 mm (a denormal in metres) made the dwell
    arcs underflow and the profile cross itself; below a picometre it is e = 0."""
    d = PAPER.with_kind(FollowerKind.double_roller)
    tiny = d.model_copy(update={"follower": d.follower.model_copy(update={"offset_mm": 2e-313})})
    zero = d.model_copy(update={"follower": d.follower.model_copy(update={"offset_mm": 0.0})})
    a, b = analyze(tiny, verify=False), analyze(zero, verify=False)
    assert len(a.geo.faces) == 1 and a.geo.e == 0.0
    assert [v.code for v in a.violations] == [v.code for v in b.violations]


def _norton_radial_roller_rho_mm(rb, rc, h, rise, dwell, fall, n=400_000):
    """The cam's radius of curvature [mm] of a radial roller follower with cycloidal rise
    and fall, by Norton's closed form (Design of Machinery, Eq. 8.33): rho_pitch =
    ((R_p + s)^2 + s'^2)^1.5 / ((R_p + s)^2 + 2 s'^2 - s'' (R_p + s)), rho = rho_pitch
    - R_f, R_p = r_b + R_f; s', s'' per radian. Nothing of camcore's."""
    th = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    b1, t2, b3 = math.radians(rise), math.radians(rise + dwell), math.radians(fall)
    s, v, acc = np.zeros(n), np.zeros(n), np.zeros(n)
    for lo, beta, sign in ((0.0, b1, 1.0), (t2, b3, -1.0)):
        m = (th >= lo) & (th < lo + beta)
        x = (th[m] - lo) / beta
        cyc = h * (x - np.sin(2 * np.pi * x) / (2 * np.pi))
        s[m] = cyc if sign > 0 else h - cyc
        v[m] = sign * h / beta * (1 - np.cos(2 * np.pi * x))
        acc[m] = sign * 2 * np.pi * h / beta**2 * np.sin(2 * np.pi * x)
    s[(th >= b1) & (th < t2)] = h
    R = rb + rc + s
    return (R**2 + v**2) ** 1.5 / (R**2 + 2 * v**2 - acc * R) - rc


def test_convex_and_concave_radii_match_the_textbook_closed_form():
    """A designer's review: a roller cam with a concave flank reported rho as a signed
    [min, max] (-24057 .. 13031 mm: a near-inflection and the flattest concave point).
    The report gives the smallest convex rho and the tightest concave |rho|, here
    against Norton's closed form for a radial roller on a fine grid of its own."""
    from camcore.report import summary

    data = load_preset("paper_example").with_kind("single_roller").model_dump(mode="json")
    data["follower"]["single_offset_mm"] = 0.0
    data["cam"]["base_radius_mm"] = 40.0
    data["motion"].update(lift_mm=30.0, rise_deg=80.0, high_dwell_deg=70.0, fall_deg=130.0)
    data["limits"]["max_pressure_angle_deg"] = 45.0
    s = summary(analyze(Design.model_validate(data), verify=False))["radius_of_curvature_mm"]
    rho = _norton_radial_roller_rho_mm(40.0, 8.0, 30.0, 80.0, 70.0, 130.0)
    assert s["convex_min"] == pytest.approx(rho[rho > 0].min(), rel=1e-4)
    assert s["concave_min"] == pytest.approx(-rho[rho < 0].max(), rel=1e-4)
    paper = summary(analyze(load_preset("paper_example"), verify=False))
    assert paper["radius_of_curvature_mm"]["concave_min"] is None  # Eq. 22: convex
    lo = min(paper["curvature_radius_mm"]["rise"][0], paper["curvature_radius_mm"]["fall"][0])
    assert paper["radius_of_curvature_mm"]["convex_min"] <= lo  # dwells included


def test_a_run_through_theta_0_is_said_as_one():
    """A broken stretch that goes on through theta = 0 was said as two ("0-5, 355-359.9"):
    on the whole-turn grid its last part now ends at 360 and the words make it one;
    the data keeps its two parts in [0, 360]. A run that does not reach both ends, a
    partial grid, and a whole turn stay as they were."""
    from camcore.checks import runs_deg, where_text

    theta = np.radians(np.arange(3600) * 0.1)
    mask = (theta < np.radians(5.05)) | (theta > np.radians(354.95))
    mask |= (theta > np.radians(99.95)) & (theta < np.radians(110.05))
    ranges = runs_deg(theta, mask)
    assert ranges == ((0.0, 5.0), (100.0, 110.0), (355.0, 360.0))
    assert where_text(ranges) == "theta = 355-5 (through 0), 100-110 deg"
    assert where_text(runs_deg(theta, theta < np.radians(5.05))) == "theta = 0-5 deg"
    assert runs_deg(theta[:1800], mask[:1800]) == ((0.0, 5.0), (100.0, 110.0))
    assert where_text(runs_deg(theta, np.ones(3600, bool))) == "theta = 0-360 deg"
    # a bracket found between the samples across theta = 0 (extremes.brackets) alike
    extra = ((np.radians(-0.1), np.radians(0.1)),)
    assert where_text(runs_deg(theta, np.zeros(3600, bool), extra)) == (
        "theta = 359.9-0.1 (through 0) deg"
    )
    # several violations' ranges (the cusp note joins two codes): merged first
    from camcore.checks import merged_deg

    assert where_text(merged_deg([(0, 5), (0, 360)])) == "theta = 0-360 deg"
    assert where_text(merged_deg([(355, 360), (0, 3), (0, 5)])) == "theta = 355-5 (through 0) deg"


def _top_peaks_by_hand(values, mask, c):
    """top_peaks by its definition, one row and one sample at a time."""
    out = []
    for i, (v, m) in enumerate(zip(values, mask, strict=True)):
        n = v.size
        peaks = [
            k
            for k in range(n)
            if m[k]
            and np.isfinite(v[k])
            and (k == 0 or not m[k - 1] or v[k] >= v[k - 1])
            and (k == n - 1 or not m[k + 1] or v[k] >= v[k + 1])
        ]
        out += [(i, k) for k in sorted(peaks, key=lambda k: (-_height(v, m, k), k))[:c]]
    return out


def _height(v, m, k) -> float:
    """What the local maximum k may reach between its neighbours, by hand: the vertex of
    the parabola through the three samples where k is above both (a missing or
    non-finite neighbour is the sample itself), at most the drop to the lower
    neighbour above the sample."""
    n = v.size
    left = v[k - 1] if k > 0 and m[k - 1] and np.isfinite(v[k - 1]) else v[k]
    right = v[k + 1] if k < n - 1 and m[k + 1] and np.isfinite(v[k + 1]) else v[k]
    strict = v[k] > left and v[k] > right  # (a plateau's sample stays as it is)
    rise = (right - left) ** 2 / (8 * (2 * v[k] - left - right)) if strict else 0.0
    return v[k] + min(max(rise, 0.0), v[k] - min(left, right))


@pytest.mark.parametrize("seed", range(6))
def test_top_peaks_takes_the_largest_local_maxima_the_earlier_of_ties(seed):
    """extremes.top_peaks against its definition on rows with plateaus (a dwell), ties
    between plateaus, masked stretches, NaN and -inf: the plateau's samples past the
    first CANDIDATES are dropped before the sort (a sweep's spring needs spent a tenth
    of the run sorting dwells), and nothing else changes; maxima ranked by the height
    they may reach between their neighbours."""
    from camcore import extremes

    rng = np.random.default_rng(seed)
    values = np.round(rng.normal(size=(7, 400)), 1)  # coarse: many equal neighbours
    values[0, 50:300] = 3.0  # a long plateau, the row's top
    values[1, 10:200] = values[1, 250:390] = 2.0  # two equal plateaus
    values[2] = 1.0  # all one plateau
    values[3, ::7] = np.nan
    values[4, 100:] = -np.inf
    mask = rng.random(values.shape) > 0.1
    mask[5] = False
    row, k = extremes.top_peaks(values, mask)
    assert list(zip(row.tolist(), k.tolist(), strict=True)) == _top_peaks_by_hand(
        values, mask, extremes.CANDIDATES
    )


def test_the_area_does_not_depend_on_blas_threads():
    """A review: a sweep's Dask workers (BLAS on one thread) gave a profile area 4e-14
    apart from the same design's report (BLAS on all threads: np.dot sums in another
    order), so a row no longer equalled its report. Same design, same area, whatever
    the threads."""
    import os
    import subprocess
    import sys

    code = (
        "import camcore\n"
        "from camcore.model import Design\n"
        "d = camcore.load_preset('paper_example').model_dump()\n"
        "d['follower']['kind'] = 'double_roller'\n"
        "d['cam']['base_radius_mm'] = 10000.0\n"
        "a = camcore.analyze(Design.model_validate(d), verify=False)\n"
        "print(repr(a.profile.area))\n"
    )
    areas = set()
    for threads in ("1", None):
        env = {k: v for k, v in os.environ.items() if not k.endswith("_NUM_THREADS")}
        if threads:
            env |= {"OPENBLAS_NUM_THREADS": threads, "OMP_NUM_THREADS": threads}
        run = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
        assert run.returncode == 0, run.stderr
        areas.add(run.stdout.strip())
    assert len(areas) == 1, areas
