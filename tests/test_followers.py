"""The followers beyond the paper's four (issue 10): offset single followers, the
flat-faced follower and the knife edge, each checked against a closed form or an
independent construction, not against the code path that produced it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from camcore import checks
from camcore.analysis import analyze
from camcore.model import Design, FollowerKind, load_preset
from camcore.motion import program
from camcore.report import summary

PAPER = load_preset("paper_example")


def design(kind: str, e_s: float = 0.0, **changes) -> Design:
    data = PAPER.with_kind(kind).model_dump()
    data["follower"]["single_offset_mm"] = e_s
    for path, value in changes.items():
        part, name = path.split("__")
        data[part][name] = value
    return Design.model_validate(data)


# --- flat face ----------------------------------------------------------------------------


def test_flat_face_profile_is_the_envelope_of_the_face_lines():
    """The classic construction: in the cam frame the face at cam angle theta is the line
    n(theta) . p = r_b + S(theta), n = R(theta) (0, 1). Consecutive lines intersect on the
    envelope; those intersections (computed by solving 2x2 systems, nothing from
    camcore.profile) must lie on the exported polyline, and rho = r_b + S + S'' must
    match the envelope's curvature from three neighbouring intersections."""
    a = analyze(design("flat_face"))
    assert a.valid, [v.message for v in a.violations]
    th = np.radians(np.linspace(0, 360, 7201))
    p = program(a.design, th)
    Y = a.geo.r_b + p.S
    n = np.stack([-np.sin(th), np.cos(th)], -1)  # R(theta) (0, 1), Eq. 11
    # intersection of line k and line k + 1
    a11, a12, a21, a22 = n[:-1, 0], n[:-1, 1], n[1:, 0], n[1:, 1]
    det = a11 * a22 - a12 * a21
    x = (Y[:-1] * a22 - a12 * Y[1:]) / det
    y = (a11 * Y[1:] - a21 * Y[:-1]) / det
    env = np.stack([x, y], -1)
    # every envelope point on the polyline (to the chordal tolerance + the O(dtheta^2)
    # error of the intersection construction)
    P = a.profile.points
    ang = np.arctan2(P[:, 1], P[:, 0])
    order = np.argsort(ang)
    k = order[np.searchsorted(ang[order], np.arctan2(env[:, 1], env[:, 0])) % len(P)]
    Q = np.roll(P, -1, axis=0)
    best = np.full(len(env), np.inf)
    for shift in range(-3, 3):
        i = (k + shift) % len(P)
        d = Q[i] - P[i]
        t = np.clip(np.einsum("ij,ij->i", env - P[i], d) / np.einsum("ij,ij->i", d, d), 0, 1)
        best = np.minimum(best, np.hypot(*(P[i] + t[:, None] * d - env).T))
    assert best.max() < 2e-6  # metres
    # curvature of the envelope through three consecutive points (circumradius)
    p0, p1, p2 = env[:-2], env[1:-1], env[2:]
    l01, l12, l02 = (np.hypot(*(u - v).T) for u, v in ((p0, p1), (p1, p2), (p0, p2)))
    cross = np.abs((p1 - p0)[:, 0] * (p2 - p0)[:, 1] - (p1 - p0)[:, 1] * (p2 - p0)[:, 0])
    circum = l01 * l12 * l02 / (2 * cross)
    mid = 0.5 * (th[1:-2] + th[2:-1])
    q = program(a.design, mid)
    classic = a.geo.r_b + q.S + q.A  # rho = r_b + S + S''
    np.testing.assert_allclose(circum, classic, rtol=2e-3)
    # and what the analysis reports is that closed form
    np.testing.assert_allclose(a.rho[0], a.geo.r_b + a.prog.S + a.prog.A, rtol=1e-12)


def test_flat_face_pressure_angle_zero_and_face_width():
    a = analyze(design("flat_face", e_s=7.0))
    assert np.all(a.pressure_angle == 0.0)
    s = summary(a)
    # the contact wanders to X = -V; from the axis at X = -7 mm: 2 max |V - 7 mm|
    V = a.prog.V * 1e3
    assert s["flat_face_width_min_mm"] == pytest.approx(2 * np.abs(-V + 7.0).max())
    # cycloidal rise h = 15 mm over 100 deg: V_max = 2 h / beta = 17.19 mm/rad
    assert np.abs(V).max() == pytest.approx(2 * 15 / math.radians(100), rel=1e-4)


def test_flat_face_cusp_is_a_violation():
    """rho = r_b + S + S'' < 0: a small base circle under a fast modified-sine rise."""
    d = design("flat_face", cam__base_radius_mm=10.0, motion__rise_deg=40.0)
    a = analyze(d)
    v = {v.code: v for v in a.violations}["curvature_convex"]
    rho_min = float((a.geo.r_b + a.prog.S + a.prog.A).min()) * 1e3
    assert rho_min < 0 and v.amount >= -rho_min * 0.999 and v.ranges_deg


# --- offset single followers ----------------------------------------------------------------


@pytest.mark.parametrize(
    "kind, e_s",
    [
        ("single_roller", 20.0),
        ("single_roller", -12.0),
        ("single_concave", 30.0),
        ("knife_edge", 15.0),
    ],
)
def test_offset_single_follower_pressure_angle_from_the_made_cam(kind, e_s):
    """The pressure angle measured on the finished polyline: at each cam angle take the
    exported profile near the contact point, its tangent by a chord through the two
    neighbouring vertices, and the angle between the normal and the follower's axis.
    It must equal Norton's closed form for an offset roller follower,
    phi = atan((V - e) / (S + sqrt(R_p^2 - e^2))), R_p = r_b + r (Cam Design and
    Manufacturing Handbook, ch. 7), here with e = e_s, and the geometric check pass."""
    d = design(kind, e_s=e_s)
    a = analyze(d)
    assert a.lift_error <= checks.lift_tolerance(a)
    r = a.geo.r
    e = e_s * 1e-3
    Rp = abs(a.geo.r_b + r)
    norton = np.arctan((a.prog.V - e) / (a.prog.S + math.sqrt(Rp**2 - e**2)))
    if r < 0:  # a concave face: the centre is below the axis (Y_C = -(L)), same formula
        norton = np.arctan((a.prog.V - e) / np.abs(a.geo.y0 + a.prog.S))
    np.testing.assert_allclose(a.pressure_angle[0], norton, atol=1e-12)
    # the same angle from the polyline (independent of the synthesis formulas): the
    # normal of the circle through the three vertices nearest the contact point
    P = a.profile.points
    for k in range(0, a.theta.size, 37):
        body = a.point_body[0, k]
        j = int(np.argmin(np.hypot(*(P - body).T)))
        centre = _circumcentre(P[j - 1], P[j], P[(j + 1) % len(P)])
        normal = body - centre
        c, s = math.cos(a.theta[k]), math.sin(a.theta[k])
        world = np.array([c * normal[0] + s * normal[1], -s * normal[0] + c * normal[1]])
        measured = math.atan(world[0] / world[1])  # the normal's tilt from the axis
        assert abs(abs(measured) - abs(a.pressure_angle[0, k])) < 2e-4, k


def _circumcentre(p, q, r):
    d = 2 * (p[0] * (q[1] - r[1]) + q[0] * (r[1] - p[1]) + r[0] * (p[1] - q[1]))
    ux = ((p @ p) * (q[1] - r[1]) + (q @ q) * (r[1] - p[1]) + (r @ r) * (p[1] - q[1])) / d
    uy = ((p @ p) * (r[0] - q[0]) + (q @ q) * (p[0] - r[0]) + (r @ r) * (q[0] - p[0])) / d
    return np.array([ux, uy])


def test_offset_lowers_the_rise_pressure_angle():
    """The documented sign: e_s > 0 (axis to the left) lowers the rise's maximum
    pressure angle and raises the fall's, for the clockwise cam."""
    base = summary(analyze(design("single_roller"), verify=False))["pressure_angle_max_deg"]
    off = summary(analyze(design("single_roller", e_s=15.0), verify=False))
    off = off["pressure_angle_max_deg"]
    assert off["rise"] < base["rise"] and off["fall"] > base["fall"]


def test_a_large_offset_raises_the_rise_pressure_angle_again():
    """The limit of the documented sign (README, Offset single followers; found by an
    independent review): past about the rise's largest V the resting follower's lean
    atan(e_s / Y_C) sets the rise's maximum, which then grows with e_s (the README's
    figures of it: tests/test_readme_numbers.py)."""
    rise = {
        e_s: summary(analyze(design("single_roller", e_s=e_s), verify=False))[
            "pressure_angle_max_deg"
        ]["rise"]
        for e_s in (0.0, 10.0, 15.0, 20.0)
    }
    assert rise[10.0] < rise[15.0] < rise[0.0] < rise[20.0]  # falls, then rises past e = 0
    a = analyze(design("single_roller", e_s=20.0), verify=False)
    R_p, e = a.geo.r_b + a.geo.r, 20e-3  # the pitch (roller centre) radius at S = 0
    lean = math.degrees(math.atan(e / math.sqrt(R_p**2 - e**2)))
    assert abs(a.pressure_angle[0, 0]) * 180 / math.pi == pytest.approx(lean, rel=1e-12)
    assert rise[20.0] == pytest.approx(lean, rel=1e-9)  # the lean at the rise's start
    v_max = float(a.prog.V.max()) * 1e3  # [mm/rad]
    assert 15.0 < v_max < 20.0  # the turn lies between the two offsets


def test_offset_beyond_the_reach_is_refused():
    with pytest.raises(ValueError, match="single_offset_mm"):
        design("single_roller", e_s=90.0)  # r_b + r_c = 88 mm


# --- knife edge ---------------------------------------------------------------------------


def test_knife_edge_profile_is_the_pitch_curve():
    """r = 0: the profile point is the follower's tip (x_c, r_b' + S) turned into the cam
    frame, so its distance from the axis is hypot(e, sqrt(r_b^2 - e^2) + S)."""
    a = analyze(design("knife_edge", e_s=10.0))
    assert a.lift_error <= checks.lift_tolerance(a)
    e = 10e-3
    expect = np.hypot(e, math.sqrt(a.geo.r_b**2 - e**2) + a.prog.S)
    np.testing.assert_allclose(np.hypot(*a.point_body[0].T), expect, rtol=1e-12)
    assert np.all(np.isnan(a.stress))
    s = summary(a)
    assert s["contact_stress_max_MPa"]["cycle"] is None
    assert "contact_stress" not in {v.code for v in a.violations}


@pytest.mark.parametrize("kind", [FollowerKind.flat_face, FollowerKind.knife_edge])
def test_new_followers_export_watertight(kind):
    import io

    import trimesh

    from camcore import export

    a = analyze(design(kind.value, e_s=5.0))
    mesh = trimesh.load(io.BytesIO(export.stl_bytes(a)), file_type="stl")
    assert mesh.is_watertight
    assert mesh.volume == pytest.approx(a.profile.area * 1e9 * 15.0 / 1e3, rel=1e-6)


def test_compare_reports_followers_the_design_cannot_take():
    """A face radius smaller than the base radius suits rollers, not concave faces:
    compare(errors=True) gives the reason for those (the app's Compare tab), and
    without errors=True the first one raises."""
    import pytest
    from pydantic import ValidationError

    from camcore.analysis import compare
    from camcore.model import load_preset

    data = load_preset("paper_example").with_kind("single_roller").model_dump(mode="json")
    data["follower"]["face_radius_mm"] = -70.0
    d = type(load_preset("paper_example")).model_validate(data)
    out = compare(d, errors=True)
    kinds = {k.value: v for k, v in out.items()}
    assert not isinstance(kinds["single_roller"], str)
    assert isinstance(kinds["double_concave"], str) and "face_radius_mm" in kinds["double_concave"]
    with pytest.raises(ValidationError):
        compare(d)


def test_compare_shares_one_grid_and_one_program():
    """Issue 12: the four followers are compared at the same angles, with the motion
    program evaluated once; every follower's stations are on that grid; each result is
    its own analysis on that grid, and agrees with its stand-alone analysis (on the
    paper example the double followers' stations add no sample the singles' grid has
    not: the worst values between samples agree to the last bit)."""
    from camcore.analysis import compare

    res = compare(PAPER)
    first = next(iter(res.values()))
    assert not isinstance(first, str)
    for kind, a in res.items():
        assert not isinstance(a, str)
        assert a.theta is first.theta and a.prog is first.prog
        assert np.all(np.isin(a.stations, a.theta)), kind
        own = analyze(PAPER.with_kind(kind), verify=False, theta=a.theta)
        np.testing.assert_array_equal(own.guide.FN, a.guide.FN)
        np.testing.assert_array_equal(own.stress, a.stress)
        alone = analyze(PAPER.with_kind(kind), verify=False)
        for name, w in a.worst.items():
            assert (w is None) == (alone.worst[name] is None)
            if w is not None:
                assert w.value == alone.worst[name].value, name
    # a double follower's stations (beta_r + 2 psi_h, ...) are on the singles' grid too
    doubles = [a.stations for k, a in res.items() if k.is_double and not isinstance(a, str)]
    assert np.all(np.isin(np.concatenate(doubles), first.theta))
    single_grid = analyze(PAPER.with_kind("single_roller"), verify=False).theta
    assert not np.all(np.isin(doubles[0], single_grid))


@pytest.mark.parametrize("kind", list(FollowerKind))
def test_a_follower_uses_exactly_the_fields_it_says(kind):
    """FollowerKind.uses (the app greys out, and Explore counts once, what a follower
    does not use): a field it does not use leaves the analysis as it was, bit for bit;
    a field it uses changes the cam or its forces."""
    base = PAPER.with_kind(kind).model_dump()
    changes = {
        "offset_mm": 25.0,
        "single_offset_mm": 4.0,
        "roller_radius_mm": 14.0,
        "face_radius_mm": -300.0,
    }
    a0 = analyze(Design.model_validate(base), verify=False)
    for name, value in changes.items():
        data = PAPER.with_kind(kind).model_dump()
        data["follower"][name] = value
        a = analyze(Design.model_validate(data), verify=False)
        same = (
            a.profile.points.shape == a0.profile.points.shape
            and np.array_equal(a.profile.points, a0.profile.points)
            and np.array_equal(a.guide.FN, a0.guide.FN)
            and np.array_equal(a.stress, a0.stress, equal_nan=True)
        )
        assert same == (not kind.uses(name)), (kind, name)


def test_a_stress_from_a_near_cusp_says_so():
    """A cam whose radius of curvature nears zero gets Hertz stresses of millions of MPa
    from Eq. 42: the message says it comes from the curvature (Eq. 21), which is what to
    fix; a stress that is simply too high (a roller against a low allowable) does not."""
    data = PAPER.model_dump()
    data["cam"]["base_radius_mm"] = 20.0
    a = analyze(Design.model_validate(data), verify=False)
    (v,) = [v for v in a.violations if v.code == "contact_stress"]
    assert "near cusp" in v.message and "Eq. 21" in v.message
    # no seven-digit "MPa" beside a headline that says unbounded: three digits at most
    assert v.message.startswith("Hertz stress without bound at theta = ")
    assert "more than a thousand times the allowable 1000 MPa" in v.message, v.message
    assert checks._times(10.0) == "ten times" and checks._times(9.9e9) == "a million times"
    assert checks._times(99_999.0) == "ten thousand times"
    # a peak between the samples, where rho nears 0 though the samples' is 0.61 mm
    data = PAPER.model_dump()
    data["cam"].update(base_radius_mm=50.0, speed_rpm=300.0)
    data["follower"].update(face_radius_mm=-75.0, offset_mm=5.0)
    a = analyze(Design.model_validate(data), verify=False)
    (v,) = [v for v in a.violations if v.code == "contact_stress"]
    assert v.message.startswith("Hertz stress without bound") and "near cusp" in v.message
    data = PAPER.with_kind("double_roller").model_dump()
    data["limits"]["allowable_contact_stress_MPa"] = 10.0
    a = analyze(Design.model_validate(data), verify=False)
    (v,) = [v for v in a.violations if v.code == "contact_stress"]
    assert v.amount > 10 * 10.0 and "cusp" not in v.message


def test_a_single_followers_text_says_no_psi_and_each_station_once():
    """A single follower's psi are 0 and its stations come in equal pairs (nothing to
    hand over): the printed report and the app's table show a dash and each angle once,
    the JSON keeps the numbers."""
    from app.panels import summary_markdown
    from camcore.report import report_text

    single = summary(analyze(load_preset("paper_example").with_kind("single_roller")))
    assert single["psi_h_deg"] == 0.0 and len(single["stations_deg"]) == 6
    text = report_text(single)
    assert "psi_h / psi_l (Eqs. 23, 25)          -\n" in text
    assert "stations                             0.000 100.000 170.000 300.000 deg" in text
    assert "– (one contact)" in summary_markdown(single)
    double = summary(analyze(load_preset("paper_example")))
    assert "3.6984 / 3.3723 deg" in report_text(double)
    assert "0.000 100.000 107.397 162.603 170.000 300.000 deg" in report_text(double)
    assert "3.698 / 3.372 °" in summary_markdown(double)


@pytest.mark.parametrize(
    "kind", ["double_concave", "single_concave", "flat_face", "single_roller", "knife_edge"]
)
def test_the_face_contact_span_is_where_the_faces_touch(kind):
    """face_contact_x_mm: the stretch of a concave pad or a flat face the contact runs
    over (a maker's review: a concave follower could not be sized). Each end is a
    contact point at some angle of the grid, every contact point lies within it, and a
    flat face's span gives its width figure; a roller turns and a knife edge is its tip,
    so neither has one."""
    a = analyze(load_preset("paper_example").with_kind(kind))
    spans = summary(a)["face_contact_x_mm"]
    if kind in ("single_roller", "knife_edge"):
        assert spans == {"face1": None, "face2": None}
        return
    for i in range(len(a.geo.faces)):
        lo, hi = spans[f"face{i + 1}"]
        x = (a.point_world[i, a.in_contact[i], 0] - a.geo.stem_x) * 1e3
        assert lo == pytest.approx(x.min(), abs=1e-12) and hi == pytest.approx(x.max(), abs=1e-12)
        assert lo < hi
    if kind == "double_concave":  # S1 works left of the axis, S2 right of it
        assert spans["face1"][1] < 0 < spans["face2"][0]
        text = __import__("camcore.report", fromlist=["report_text"]).report_text(summary(a))
        lo1, hi1, lo2, hi2 = (f"{v:.2f}" for v in (*spans["face1"], *spans["face2"]))
        assert f"S1 {lo1} .. {hi1} / S2 {lo2} .. {hi2} mm" in text  # each face named
    else:
        assert spans["face2"] is None
    if kind == "flat_face":
        lo, hi = spans["face1"]
        width = summary(a)["flat_face_width_min_mm"]
        assert width == pytest.approx(2 * max(-lo, hi), rel=1e-12)


@pytest.mark.parametrize(("e", "broken"), [(5.0, True), (8.0, True), (8.5, False), (0.0, False)])
def test_double_rollers_must_not_touch(e, broken):
    """Two rollers of r_c = 8 mm at X = +-e: overlapping (e < r_c) or touching (e = r_c)
    is a violation (a designer's review: they were valid, and led a sweep's front);
    e = 0 is one roller. The batched core of sweeps says the same."""
    from camcore import batch

    data = load_preset("paper_example").with_kind("double_roller").model_dump()
    data["follower"]["offset_mm"] = e
    d = Design.model_validate(data)
    codes = [v.code for v in analyze(d, verify=False).violations]
    assert ("rollers_overlap" in codes) == broken
    assert [v["code"] for v in batch.summaries([d])[0]["violations"]] == codes
    if broken and e < 8.0:
        (v,) = [v for v in analyze(d, verify=False).violations if v.code == "rollers_overlap"]
        assert "overlap by 6 mm" in v.message and v.amount == pytest.approx(6.0)


def test_the_shared_load_stress_is_eq42_by_hand():
    """contact_stress_max_MPa.high_dwell_two_contact of the paper's double concave
    faces, by hand: F_N = F_t / (2 cos psi_h) with F_t = M g + k (h + s_p) (Eqs. 29,
    36-38), on the dwell arc R (Eq. 20) against the face r_f = -250 mm, line contact of
    width w between two steels (Eq. 42): 32.96 MPa, the Compare tab's "σ_H high dwell"."""
    d = load_preset("paper_example")
    s = summary(analyze(d, verify=False))
    Ft = 0.108 * d.dynamics.gravity_m_s2 + 6772.5 * (15e-3 + 5e-3)
    FN = Ft / (2 * math.cos(math.radians(s["psi_h_deg"])))
    curv = 1 / (s["dwell_radius_mm"] * 1e-3) - 1 / 0.250  # 1/rho - 1/|r_f|
    compliance = 2 * (1 - 0.29**2) / 210e9
    p = math.sqrt(FN / 15e-3 * curv / (math.pi * compliance))
    assert s["contact_stress_max_MPa"]["high_dwell_two_contact"] == pytest.approx(p / 1e6, rel=1e-6)
    assert p / 1e6 == pytest.approx(32.96, abs=0.01)


def test_a_flat_face_cusp_between_two_samples_is_found():
    """An adversarial review: rho = r_b + S + S'' dipped to -0.00055 mm over 0.03 deg
    between two samples (a cusp), and the design passed at 0.1 deg: the search looked
    for the least kappa_p = 1 / rho, where a dip of rho through 0 is a maximum. It
    searches rho itself now, at any resolution, in the batched core too."""
    from camcore import batch

    data = load_preset("paper_example").model_dump(mode="json")
    data["follower"]["kind"] = "flat_face"
    data["motion"]["segments"][0]["angle_deg"] = 40.0
    data["motion"]["segments"][1]["angle_deg"] = 130.0
    data["cam"].update(base_radius_mm=179.7503, speed_rpm=1.0, width_mm=1000.0)
    data["dynamics"].update(mass_g=0.001, spring_rate_N_per_m=0.0, preload_mm=0.0)
    for res in (0.1, 5.0):
        data["limits"]["resolution_deg"] = res
        d = Design.model_validate(data)
        a = analyze(d, verify=False)
        on = a.on_curve.any(axis=0)
        assert (a.rho[0][on] > 0).all()  # no sample sees it
        [v] = [v for v in a.violations if v.code == "curvature_convex"]
        assert -1e-3 < -v.amount < 0 and v.ranges_deg[0][0] <= 29.92 <= v.ranges_deg[0][1]
        row = batch.summaries([d])[0]
        assert "curvature_convex" in [v["code"] for v in row["violations"]]


def test_a_high_dwell_of_exactly_4_psi_is_not_said_to_be_shorter():
    """An adversarial review: beta_h = 4 psi_h exactly (Eq. 28 met) put station 3
    1e-14 rad before station 2 and the valid design's stations read "(station 3 before
    2: the dwell between them is shorter than 4 psi, Eq. 28)"."""
    from camcore.report import report_text

    psi = summary(analyze(PAPER, verify=False))["psi_h_deg"]
    data = PAPER.model_dump(mode="json")
    segs = data["motion"]["segments"]  # rise, high dwell, fall, low dwell

    def high_dwell(deg: float) -> None:
        segs[3]["angle_deg"] += segs[1]["angle_deg"] - deg  # (the low dwell makes up)
        segs[1]["angle_deg"] = deg

    high_dwell(4 * psi)
    d = Design.model_validate(data)
    a = analyze(d, verify=False)
    s = summary(a)
    assert s["valid"] and "high_dwell_arc" not in [v["code"] for v in s["violations"]]
    assert "shorter than 4 psi" not in report_text(s, d)
    high_dwell(4 * psi * 0.99)
    short = summary(analyze(Design.model_validate(data), verify=False))
    assert "shorter than 4 psi" in report_text(short, d)
