"""The running machine (issue 11): spring sizing, jump speed, shaft torque, power and
flywheel. Each figure is checked by a route that does not share its formula: the full
guide-force solve of Eqs. 33-41 (with friction) on both sides of the edge, closed forms,
the power balance through the instant centre, and the energy balance over a cycle."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from camcore import machine, report
from camcore.analysis import analyze
from camcore.model import Design, load_preset
from camcore.units import GRAM, MM, RPM

PAPER = load_preset("paper_example")


def tweak(design: Design, **fields) -> Design:
    """``design`` with dotted fields changed (part__field=value), validated again."""
    data = design.model_dump(mode="json")
    for key, value in fields.items():
        part, name = key.split("__")
        data[part][name] = value
    return Design.model_validate(data)


def jumps(design: Design) -> bool:
    return any(v.code == "jump" for v in analyze(design, verify=False).violations)


@pytest.mark.parametrize("kind", ["single_roller", "double_concave"])
def test_spring_rate_min_is_the_edge_of_jump(kind):
    """Just above k_min the full force solve (guide friction 0.1) keeps F_N > 0 at every
    angle, between the samples too; 2 % below it the follower jumps."""
    d = PAPER.with_kind(kind)
    a = analyze(d, verify=False)
    k_min, at = machine.spring_rate_min(d, a.theta)
    assert 0 < k_min < d.dynamics.spring_rate_N_per_m  # the paper's spring is enough
    assert not jumps(tweak(d, dynamics__spring_rate_N_per_m=k_min * 1.002))
    assert jumps(tweak(d, dynamics__spring_rate_N_per_m=k_min * 0.98))
    # the proposal keeps the design's preload and scales the rate by the safety factor,
    # rounded up to 4 significant figures: the figure shown, typed in, meets the factor
    s = machine.spring(d, a.theta)
    n = d.dynamics.spring_safety_factor
    assert n * k_min <= s.proposed_rate <= n * k_min * (1 + 1e-3)
    assert len(f"{s.proposed_rate:g}".replace(".", "").strip("0")) <= 4
    typed = report.summary(analyze(tweak(d, dynamics__spring_rate_N_per_m=s.proposed_rate)))
    assert typed["jump_margin"]["spring_rate"] >= n
    assert "close to jump" not in str(report.machine_rows(typed))


def test_the_proposed_spring_is_rounded_up_to_four_figures():
    """machine.proposed_rate against hand-rounded values (the review's 2089.334 N/m)."""
    assert machine.proposed_rate(1.5, 2089.334 / 1.5) == 2090.0
    assert machine.proposed_rate(1.0, 0.0185175) == 0.01852
    assert machine.proposed_rate(2.0, 500.0) == 1000.0  # already 4 figures: unchanged
    assert machine.proposed_rate(1.5, 0.0) == 0.0
    assert machine.proposed_rate(1.5, math.inf) == math.inf
    # decimal, not binary, rounding: no 0.001001 for 0.001, no overflow for a subnormal
    assert machine.proposed_rate(1.0, 0.001) == 0.001
    assert machine.proposed_rate(3.0, 0.1) == 0.3  # (3 x 0.1 = 0.30000000000000004)
    assert machine.proposed_rate(1.0, 1e-310) == 1e-310  # (subnormal: 1e-310 exactly)
    assert machine.proposed_rate(1.0, 5e-324) >= 5e-324
    assert machine.proposed_rate(1.0, 1000.0000005) == 1001.0  # never below n k_min
    assert machine.proposed_rate(1.0, 1.7976931348623157e308) == 1.7976931348623157e308
    assert machine.proposed_rate(1.0, 9999.5) == 10000.0
    assert machine.proposed_rate(1.0, 1.00000001) == 1.001


def test_preload_min_is_the_edge_of_jump():
    d = tweak(PAPER, dynamics__spring_rate_N_per_m=1500.0)
    a = analyze(d, verify=False)
    s_min, _ = machine.preload_min(d, a.theta)
    assert s_min > 0
    assert not jumps(tweak(d, dynamics__preload_mm=s_min / MM * 1.002))
    assert jumps(tweak(d, dynamics__preload_mm=s_min / MM * 0.98))


def test_spring_rate_min_scales_with_speed_squared():
    """Without gravity the load to hold is pure inertia, M A w^2: k_min grows as w^2."""
    d = tweak(PAPER, dynamics__gravity_m_s2=0.0)
    th = analyze(d, verify=False).theta
    k1, at1 = machine.spring_rate_min(d, th)
    k2, at2 = machine.spring_rate_min(tweak(d, cam__speed_rpm=2 * d.cam.speed_rpm), th)
    assert k2 == pytest.approx(4 * k1, rel=1e-9) and at2 == pytest.approx(at1)


def test_jump_speed_closed_form_and_full_solve():
    """With a preload far larger than the lift the spring force is nearly constant, so
    the jump speed is w^2 = k (S* + s_p) / (M 2 pi h / beta^2) at the cycloid's peak
    deceleration (x = 3/4 of the rise, S* = h (3/4 + 1/(2 pi))); and the full solve
    jumps just above the computed speed, not just below."""
    h, beta = 10.0, 80.0
    d = tweak(
        PAPER,
        dynamics__gravity_m_s2=0.0,
        dynamics__preload_mm=10000.0,
        dynamics__spring_rate_N_per_m=50.0,
        motion__lift_mm=h,
        motion__rise_deg=beta,
        motion__fall_deg=120.0,
    )
    a = analyze(d, verify=False)
    rpm, at = machine.jump_speed_rpm(d, a.theta)
    M, k, hm, b = d.dynamics.mass_g * GRAM, 50.0, h * MM, math.radians(beta)
    S_star = hm * (0.75 + 1 / (2 * math.pi))
    w = math.sqrt(k * (S_star + 10.0) / (M * 2 * math.pi * hm / b**2))
    assert rpm == pytest.approx(w / RPM, rel=1e-5)
    assert math.degrees(at) == pytest.approx(0.75 * beta, abs=0.5)
    assert not jumps(tweak(d, cam__speed_rpm=rpm * 0.995))
    assert jumps(tweak(d, cam__speed_rpm=rpm * 1.005))
    # the paper's design at its own spring: above its 1200 rpm, and the edge of jump
    a = analyze(PAPER, verify=False)
    rpm, _ = machine.jump_speed_rpm(PAPER, a.theta)
    assert rpm > PAPER.cam.speed_rpm
    assert not jumps(tweak(PAPER, cam__speed_rpm=rpm * 0.995))
    assert jumps(tweak(PAPER, cam__speed_rpm=rpm * 1.005))


def test_jump_speed_without_anything_holding_the_follower_is_zero():
    d = tweak(PAPER, cam__speed_rpm=1.0)
    a = analyze(d, verify=False)
    rpm, _ = machine.jump_speed_rpm(
        tweak(d, dynamics__spring_rate_N_per_m=0.0, dynamics__gravity_m_s2=0.0), a.theta
    )
    assert rpm == 0.0  # nothing holds the follower down: it leaves at any speed
    assert machine.jump_speed_rpm(d, a.theta)[0] > 1.0


@pytest.mark.parametrize("kind", ["single_roller", "single_concave", "double_concave", "flat_face"])
def test_torque_by_moments_equals_the_power_through_the_instant_centre(kind):
    """T from moments of the contact force about the cam centre (contact point and
    normal) equals F_N n_y V, the power given to the follower per unit cam speed (the
    normal meets the x-axis at I23, OI23 = V, Eqs. 1-4): two independent routes."""
    a = analyze(PAPER.with_kind(kind), verify=False)
    power = (a.FN * a.normal[..., 1]).sum(axis=0) * a.prog.V
    T = a.torque.sum(axis=0)
    np.testing.assert_allclose(T, power, atol=1e-9 * np.abs(T).max())
    assert np.abs(T[a.prog.V == 0]).max() == 0.0  # dwells ask nothing of the shaft


def test_frictionless_torque_integrates_to_zero_and_matches_the_energy_balance():
    """Without friction the follower stores and returns all the work: the torque
    integrates to zero over the cycle, and the flywheel's energy swing equals that of
    the follower's energy E = M g S + M w^2 V^2 / 2 + k (S + s_p)^2 / 2 (closed form
    from the motion program alone)."""
    d = tweak(PAPER, dynamics__guide_friction=0.0, limits__resolution_deg=0.05)
    a = analyze(d, verify=False)
    sh = machine.shaft(a)
    assert abs(sh.power_mean) < 1e-6 * sh.power_max
    dyn, w = d.dynamics, PAPER.cam.speed_rpm * RPM
    M, k, s_p = dyn.mass_g * GRAM, dyn.spring_rate_N_per_m, dyn.preload_mm * MM
    p = a.prog
    E = M * dyn.gravity_m_s2 * p.S + M * w**2 * p.V**2 / 2 + k * (p.S + s_p) ** 2 / 2
    assert sh.flywheel_energy == pytest.approx(E.max() - E.min(), rel=1e-3)
    assert sh.flywheel_inertia == pytest.approx(sh.flywheel_energy / (dyn.speed_fluctuation * w**2))
    # guide friction only takes: the mean power is the loss, and positive
    assert machine.shaft(analyze(PAPER, verify=False)).power_mean > 0
    # on a coarse grid too: nothing steps in this program, so the cycle's integral is
    # the plain trapezoid's (a review: extrapolating at every boundary gave -1.2e-4 W)
    coarse = machine.shaft(analyze(tweak(d, limits__resolution_deg=1.0), verify=False))
    assert abs(coarse.power_mean) < 1e-12 * coarse.power_max


def test_the_flywheel_counts_the_work_of_a_velocity_jump():
    """A dynamics review: with a constant-velocity rise (V jumps at both ends) the
    flywheel's Delta E left out the follower's kinetic-energy steps, which no torque
    sample carries: 1.2867 J against the energy balance's 1.3487 J (4.6 % low). Nor may
    the torque's integral lose the step of the torque at the jump (a later review)."""
    data = tweak(PAPER, dynamics__guide_friction=0.0).model_dump(mode="json")
    data["motion"]["segments"][0]["law"] = "constant_velocity"
    d = Design.model_validate(data)
    a = analyze(d, verify=False)
    assert "velocity_jump" in [v.code for v in a.violations]
    sh = machine.shaft(a)
    dyn, w = d.dynamics, d.cam.speed_rpm * RPM
    M, k, s_p = dyn.mass_g * GRAM, dyn.spring_rate_N_per_m, dyn.preload_mm * MM
    p = a.prog
    E = M * dyn.gravity_m_s2 * p.S + M * w**2 * p.V**2 / 2 + k * (p.S + s_p) ** 2 / 2
    assert sh.flywheel_energy == pytest.approx(E.max() - E.min(), rel=2e-3)
    # frictionless, the shaft gets all its work back: the torque's trapezoids beside a
    # jump had lost half a strip each (0.026 W of 147 W max at 0.1 deg)
    assert abs(sh.power_mean) < 1e-6 * sh.power_max
    from camcore import batch  # (the sweeps' batched core counts it alike)

    row = batch.summaries([d])[0]
    assert row["flywheel_energy_J"] == pytest.approx(sh.flywheel_energy, rel=1e-12)
    assert row["power_mean_W"] == pytest.approx(sh.power_mean, rel=1e-9, abs=0)


def test_torque_peaks_are_found_between_the_samples():
    fine = machine.shaft(analyze(tweak(PAPER, limits__resolution_deg=0.01), verify=False))
    coarse = machine.shaft(analyze(tweak(PAPER, limits__resolution_deg=2.0), verify=False))
    assert coarse.drive_max == pytest.approx(fine.drive_max, rel=1e-5)
    assert coarse.brake_max == pytest.approx(fine.brake_max, rel=1e-5)
    assert fine.power_max == pytest.approx(fine.drive_max * PAPER.cam.speed_rpm * RPM)


def test_series_csv_has_every_quantity_per_angle(tmp_path):
    """The per-angle series (CLI --series, the app's download): one row per grid angle;
    per-second motion is the per-radian motion times w, w^2, w^3 (checked on the cycloid's
    closed-form peak velocity 2 h / beta); the torque column is the shaft torque."""
    import csv
    import io

    from camcore import export

    a = analyze(PAPER, verify=False)
    rows = list(csv.DictReader(io.StringIO(export.series_csv_text(a))))
    assert len(rows) == a.theta.size
    for key in (
        "J_mm_per_rad3",
        "V_m_per_s",
        "A_m_per_s2",
        "J_m_per_s3",
        "rho_mm",
        "Ft_N",
        "FN_N_1",
        "FN_N_2",
        "stress_MPa_2",
        "cam_torque_Nm",
    ):
        assert key in rows[0]
    w = PAPER.cam.speed_rpm * RPM
    v = np.array([float(r["V_m_per_s"]) for r in rows])
    h, beta = PAPER.motion.lift_mm * MM, math.radians(PAPER.motion.rise_deg)
    assert v.max() == pytest.approx(2 * h / beta * w, rel=1e-6)  # cycloid: V_max = 2h/beta
    T = np.array([float(r["cam_torque_Nm"]) for r in rows])
    np.testing.assert_allclose(T, a.torque.sum(axis=0), rtol=1e-8, atol=1e-12)


def test_hertz_half_width_matches_the_textbook_formula():
    """b = sqrt(4 F C / (pi w (1/r + 1/rho))) (Shigley, Sec. 3-19), against ours,
    2 F / (pi w sigma), for a roller; and the paper's example is well inside validity."""
    from camcore.contact import compliance, hertz_validity
    from camcore.report import summary

    d = PAPER.with_kind("single_roller")
    a = analyze(d, verify=False)
    b, beyond = hertz_validity(d, a.FN, a.rho)
    r, w = d.follower.radius_mm * MM, d.cam.width_mm * MM
    on = a.FN > 0
    ref = np.sqrt(4 * a.FN[on] * compliance(d) / (np.pi * w * (1 / r + 1 / a.rho[on])))
    np.testing.assert_allclose(b[on], ref, rtol=1e-12)
    assert not beyond.any()
    s = summary(analyze(PAPER, verify=False))
    assert s["hertz_beyond_validity_deg"] == []
    assert 0 < s["contact_half_width_max_mm"] < 0.2


def test_conforming_concave_face_gets_the_conservative_stress():
    """A concave face 1 um larger than the high-dwell arc: the curvature sum nearly
    vanishes, Hertz's strip would be 30 mm wide and its stress tiny. There the report
    names the angles and the stress is that of the widest valid strip, higher than the
    plain formula's."""
    from camcore.contact import HERTZ_VALID_RATIO, compliance, hertz_line_stress, hertz_validity
    from camcore.report import summary

    d = PAPER.with_kind("single_concave")
    R = analyze(d, verify=False).geo.dwell_radius
    d = tweak(d, follower__face_radius_mm=-(R / MM + 0.001))
    a = analyze(d, verify=False)
    high = a.prog.segment == 1
    b, beyond = hertz_validity(d, a.FN, a.rho)
    assert beyond[0, high].all()
    w = d.cam.width_mm * MM
    plain = hertz_line_stress(a.FN, d.follower.radius_mm * MM, a.rho, w, compliance(d))
    k = np.flatnonzero(high)[0]
    expected = 2 * a.FN[0, k] / (np.pi * w * HERTZ_VALID_RATIO * R)
    assert a.stress[0, k] == pytest.approx(expected, rel=1e-9)
    assert a.stress[0, k] > 2 * plain[0, k]
    s = summary(a)
    at = math.degrees(a.theta[k])
    assert any(lo <= at <= hi for lo, hi in s["hertz_beyond_validity_deg"])


def test_flat_face_sliding_speed_is_the_classic_closed_form():
    """A translating flat face: the contact runs along the cam at (r_b + S + A) w and
    along the face at A w, so it slides at w (r_b + S) (e.g. Norton, flat-faced
    follower kinematics); wear per pass k F_N / w_cam times (r_b + S) / (r_b + S + A)."""
    from camcore import wear

    d = PAPER.with_kind("flat_face")
    a = analyze(d, verify=False)
    w, rb = d.cam.speed_rpm * RPM, d.cam.base_radius_mm * MM
    S, A = a.prog.S, a.prog.A
    np.testing.assert_allclose(wear.sliding_speed(a)[0], w * (rb + S), rtol=1e-9)
    k = d.wear.coefficient_mm3_per_N_m * 1e-9
    expected = k * a.FN[0] / (d.cam.width_mm * MM) * (rb + S) / (rb + S + A)
    np.testing.assert_allclose(wear.depth_per_pass(a)[0], expected, rtol=1e-9)


@pytest.mark.parametrize("kind", ["single_concave", "double_concave", "knife_edge"])
def test_on_a_dwell_the_cam_slides_under_the_face(kind):
    """On a dwell arc the follower rests: all the cam's surface speed is sliding,
    v_s = u = w R, and each pass wears k F_N / w_cam (Archard: volume k F s over the
    strip's area w s)."""
    from camcore import wear

    d = PAPER.with_kind(kind)
    a = analyze(d, verify=False)
    dwell = a.in_contact & (a.prog.V == 0)[None, :]
    np.testing.assert_allclose(wear.sliding_ratio(a)[dwell], 1.0, rtol=1e-9)
    k = d.wear.coefficient_mm3_per_N_m * 1e-9
    np.testing.assert_allclose(
        wear.depth_per_pass(a)[dwell], k * a.FN[dwell] / (d.cam.width_mm * MM), rtol=1e-9
    )


def test_rollers_roll_and_passes_add_up_along_the_profile():
    from camcore import wear

    a = analyze(PAPER.with_kind("double_roller"), verify=False)
    assert not wear.depth_per_pass(a).any()
    # a double concave follower: both faces slide over the high-dwell arc, and a point
    # of it collects one pass of each (the bins hold the sum)
    a = analyze(PAPER, verify=False)
    h = wear.depth_per_pass(a)
    phi, depth = wear.along_profile(a, bins=360)
    assert depth.max() > h.max()  # two passes on the arc beat any single pass
    assert depth.max() <= h[0].max() + h[1].max() + 1e-30
    # the curve of the total at the touched point (the app's wear plot) reaches the
    # reported peak, and is never below a single pass where that face touches
    total = wear.total_at_contacts(a)
    assert total.max() == depth.max()
    assert np.all(total >= np.where(a.in_contact, h, 0.0).max(axis=0))
    assert np.all(total[~a.in_contact.any(axis=0)] == 0.0)


def _archard_in_time(design, resolution_deg, sigma):
    """Peak wear depth per cycle [m] by a model independent of camcore.wear's: run the
    cam through a cycle and let each face, at each step dt, wear k F_N v_s dt / w_cam
    (Archard's volume over the cam's width) spread along the cam around its contact
    point as a Gaussian of width sigma [m]; add everything up at every contact point.
    No passes, no travel speed u, no pairing of faces: only where each face is when."""
    from scipy.spatial import cKDTree

    from camcore.forces import tangential_slip
    from camcore.model import omega_rad_s

    d = design.model_copy(
        update={"limits": design.limits.model_copy(update={"resolution_deg": resolution_deg})}
    )
    a = analyze(d, verify=False)
    w = omega_rad_s(d)
    dt = np.gradient(a.theta) / w
    v_s = np.abs(tangential_slip(a.point_world, a.normal, a.prog.V)) * w
    k = d.wear.coefficient_mm3_per_N_m * 1e-9
    on = a.in_contact
    points = a.point_body[on]
    worn = (k * np.maximum(a.FN, 0.0) * v_s * dt[None, :] / (d.cam.width_mm * MM))[on]
    tree = cKDTree(points)
    depth = np.zeros(len(points))
    for i, near in enumerate(tree.query_ball_point(points, 4 * sigma)):
        r = np.linalg.norm(points[near] - points[i], axis=1)
        depth[i] = worn[near] @ np.exp(-0.5 * (r / sigma) ** 2) / (np.sqrt(2 * np.pi) * sigma)
    return depth.max()


@pytest.mark.parametrize(
    "preset, kind",
    [
        ("classroom_harmonic", "double_concave"),  # the faces meet where the rise ends
        ("paper_example", "double_concave"),
        ("paper_example", "knife_edge"),
    ],
)
def test_the_wear_peak_agrees_with_archard_run_in_time(preset, kind):
    """The reported peak wear (camcore.wear.along_profile, per pass, at the design's
    0.1 deg) against the time-stepped model above at 0.02 deg. A review found a double
    follower's peak 21 % high when each face's largest pass per bin of the cam was added
    to the other's: near the end of classroom_harmonic's rise, the two came from
    different cam points."""
    from camcore import wear

    d = load_preset(preset).with_kind(kind)
    reported = wear.along_profile(analyze(d, verify=False))[1].max()
    assert reported == pytest.approx(_archard_in_time(d, 0.02, 0.1e-3), rel=2e-3, abs=0)


def test_pitting_life_follows_the_stress_life_curve():
    """N = N_ref (sigma_allow / sigma_max)^m: with the allowable set to half the
    design's peak stress the life is N_ref / 2^m; within the allowable, endurance. The
    peak is the real cam's (the report's figure, found between the samples too)."""
    from camcore import wear
    from camcore.report import summary

    a = analyze(PAPER, verify=False)
    s_max = summary(a)["contact_stress_max_MPa"]["cycle"]
    assert s_max > a.stress.max() / 1e6  # (the paper example's peak is at a rise's end)
    assert wear.pitting_life_cycles(a) == math.inf
    d = tweak(PAPER, limits__allowable_contact_stress_MPa=s_max / 2)
    life = wear.pitting_life_cycles(analyze(d, verify=False))
    assert life == pytest.approx(d.wear.pitting_reference_cycles / 2**d.wear.pitting_exponent)


@pytest.mark.parametrize(
    "kind", ["single_concave", "double_concave", "flat_face", "knife_edge", "double_roller"]
)
def test_contact_friction_power_balance(kind):
    """With sliding friction at the contact (mu_c) and in the guide (mu), the shaft's
    power at every angle is the follower's power plus what both frictions dissipate:
    T = F_t V + mu_c sum F_N |v_s| / w + mu (F1 + F2) |V|. T comes from moments about
    the cam centre, the rest from the kinematics and the solved forces: this checks the
    friction's direction, its moment in the guide solve, and the two-contact dwell.
    Rollers roll: mu_c changes nothing for them."""
    from camcore import wear

    d = tweak(PAPER.with_kind(kind), dynamics__contact_friction=0.1)
    a = analyze(d, verify=False)
    w = d.cam.speed_rpm * RPM
    slip = wear.sliding_speed(a) / w  # |v_s| / w per face [m/rad]
    mu, mu_c = d.dynamics.guide_friction, 0.1
    rolls = kind == "double_roller"
    expected = (
        a.Ft * a.prog.V
        + (0.0 if rolls else mu_c) * (a.FN * slip).sum(axis=0)
        + mu * (a.guide.F1 + a.guide.F2) * np.abs(a.prog.V)
    )
    ok = a.guide.mode >= 0  # where the guide does not self-lock
    T = a.torque.sum(axis=0)
    np.testing.assert_allclose(T[ok], expected[ok], atol=1e-9 * np.abs(T).max())
    base = analyze(PAPER.with_kind(kind), verify=False)
    if rolls:
        np.testing.assert_allclose(a.guide.FN, base.guide.FN)
    else:  # friction changes the forces and costs power
        assert np.abs(a.guide.FN - base.guide.FN).max() > 0.1
        assert machine.shaft(a).power_mean > machine.shaft(base).power_mean


def test_a_third_of_the_spring_mass_moves_with_the_follower_in_every_model():
    """A designer's review: the spring's own mass m_s reached only the elastic train, so
    the rigid model passed a design that jumps (and the train, made as stiff as rigid,
    said it jumps). m = M + m_s / 3 everywhere: a 108 g follower with a 90 g spring is a
    138 g follower with a massless one, in every figure; the train agrees."""
    heavy_spring = tweak(PAPER, dynamics__spring_mass_g=90.0)
    heavier = tweak(PAPER, dynamics__mass_g=108.0 + 90.0 / 3)
    a, b = analyze(heavy_spring, verify=False), analyze(heavier, verify=False)
    np.testing.assert_allclose(a.Ft, b.Ft, rtol=1e-12)
    np.testing.assert_allclose(a.guide.FN, b.guide.FN, rtol=1e-12)
    for figure in (machine.spring_rate_min, machine.preload_min, machine.jump_speed_rpm):
        assert figure(heavy_spring, a.theta) == pytest.approx(figure(heavier, b.theta))
    assert (
        machine.jump_speed_rpm(heavy_spring, a.theta)[0] < machine.jump_speed_rpm(PAPER, a.theta)[0]
    )
    # just past the rigid model's jump speed, a train as stiff as rigid jumps too
    w_j = machine.jump_speed_rpm(heavy_spring, a.theta)[0]
    fast = tweak(heavy_spring, cam__speed_rpm=1.02 * w_j)
    assert jumps(fast)
    rigid_train = tweak(fast, dynamics__train_stiffness_N_per_m=1e12)
    assert any(v.code == "dynamic_jump" for v in analyze(rigid_train, verify=False).violations)
    slow = tweak(heavy_spring, cam__speed_rpm=0.98 * w_j)
    assert not jumps(slow)


def test_the_margin_to_jump_is_said_beside_the_safety_factor():
    """A designer's review: a design at 98.7 % of its jump speed read 'All limits met'
    and nothing said how close it was. The report gives k / k_min and the jump speed
    over the running speed, flagged below the spring's safety factor (not a limit)."""
    from camcore.report import machine_rows, summary

    s = summary(analyze(PAPER, verify=False))
    m = s["jump_margin"]
    assert m["spring_rate"] == pytest.approx(6772.5 / s["spring_rate_min_N_per_m"])
    assert m["jump_speed"] == pytest.approx(s["jump_speed_rpm"] / PAPER.cam.speed_rpm)
    row = dict(machine_rows(s))["margin to jump"]
    down = math.floor(6772.5 / s["spring_rate_min_N_per_m"] * 100) / 100
    assert "close to jump" not in row and f"k = {down:.2f} k_min" in row
    # k_min grows as w^2: at 1.4 x the speed, k / k_min falls below 1.5 (still valid)
    near = tweak(PAPER, cam__speed_rpm=1.4 * PAPER.cam.speed_rpm)
    s2 = summary(analyze(near, verify=False))
    assert s2["valid"] and s2["jump_margin"]["spring_rate"] < 1.5
    assert "below the safety factor 1.5: close to jump" in dict(machine_rows(s2))["margin to jump"]
    loose = tweak(PAPER, dynamics__spring_rate_N_per_m=0.0, dynamics__gravity_m_s2=0.0)
    assert summary(analyze(loose, verify=False))["jump_margin"]["spring_rate"] == 0.0


def test_a_margin_just_under_the_safety_factor_does_not_print_as_it():
    """A review: k = 1.4996 k_min printed 'k = 1.5 k_min (below the safety factor 1.5)'."""
    from camcore.report import _margin_text

    s = {"jump_margin": {"spring_rate": 1.4996, "jump_speed": 0.9996}}
    s["spring_proposal"] = {"safety_factor": 1.5}
    text = _margin_text(s)
    assert "k = 1.49 k_min" in text and "jumps at 0.99 x" in text and "close to jump" in text


def test_an_instant_drop_in_velocity_jumps_at_any_speed():
    """A teacher's review: a constant-velocity rise (V drops to 0 at its end: A = -inf)
    read 'jumps at 2411 rpm' at 1200 rpm: the grid's samples miss the impulse. No
    spring holds the follower there and it leaves the cam at any speed; a jump up
    (the cam pushing) is not a jump."""
    from camcore import machine, motion
    from camcore.analysis import analyze
    from camcore.model import Design, load_preset
    from camcore.report import report_text, summary

    data = load_preset("paper_example").model_dump()
    data["motion"]["segments"][0]["law"] = "constant_velocity"
    d = Design.model_validate(data)
    assert machine.velocity_drop(motion.segments(d)) == pytest.approx(math.radians(100.0))
    s = summary(analyze(d, verify=False))
    assert s["jump_speed_rpm"] == 0.0 and s["spring_rate_min_N_per_m"] is None
    text = report_text(s)
    assert "jump speed                           at any speed\n" in text
    assert "none: the follower leaves the cam at any speed" in text
    assert machine.velocity_drop(motion.segments(load_preset("paper_example"))) is None


def test_a_jump_speed_margin_is_a_limit_when_set():
    """limits.min_jump_speed_ratio (a designer's margin): the paper's design jumps at
    1.55 x its speed, so a margin of 1.5 holds and 1.6 is broken, by 1.6 - 1.55 at the
    angle that sets the jump speed; unset, nothing is checked beyond the speed itself.
    The speed it names is the edge of jump: run there, the contact force reaches 0."""
    from camcore.checks import run_all

    a = analyze(PAPER, verify=False)
    rpm, at = machine.jump_speed_rpm(PAPER, a.theta)
    ratio = rpm / PAPER.cam.speed_rpm
    assert 1.5 < ratio < 1.6

    def margin(lim):
        d = tweak(PAPER, limits__min_jump_speed_ratio=lim)
        return [v for v in analyze(d, verify=False).violations if v.code == "jump_speed"]

    assert margin(None) == [] and margin(1.5) == []
    (v,) = margin(1.6)
    assert v.amount == pytest.approx(1.6 - ratio, rel=1e-12)
    assert v.ranges_deg == ((pytest.approx(math.degrees(at)),) * 2,)
    down = math.floor(ratio * 100) / 100  # rounded down: 1.5999 must not read "1.60"
    assert f"from {rpm:.0f} rpm, {down:.2f} x the cam speed" in v.message
    assert "limits.min_jump_speed_ratio" in v.message
    assert v.equation == "Eq. 29 (jump speed)"
    assert jumps(tweak(PAPER, cam__speed_rpm=rpm * 1.005))  # the named speed is jump's
    # the spring it proposes meets the margin as typed in; 1 % less does not
    k = float(re.search(r"a spring rate of (\S+) N/m or more", v.message).group(1))
    stiff = tweak(PAPER, limits__min_jump_speed_ratio=1.6, dynamics__spring_rate_N_per_m=k)
    assert "jump_speed" not in {v.code for v in analyze(stiff, verify=False).violations}
    soft = tweak(stiff, dynamics__spring_rate_N_per_m=0.999 * k)
    (v,) = [v for v in analyze(soft, verify=False).violations if v.code == "jump_speed"]
    assert "1.59 x the cam speed" in v.message  # not "1.6 x ..., below the margin 1.6 x"
    # an instant drop in velocity: no spring helps, the law must change (a review)
    drop = tweak(PAPER, limits__min_jump_speed_ratio=1.3)
    data = drop.model_dump()
    data["motion"]["segments"][0]["law"] = "constant_velocity"
    (v,) = [
        v
        for v in analyze(Design.model_validate(data), verify=False).violations
        if v.code == "jump_speed"
    ]
    assert "the velocity drops instantly at theta = 100.0 deg" in v.message
    assert "a law without the drop" in v.message and "preload" not in v.message
    assert v.ranges_deg == ((100.0, 100.0),)
    # and the report's proposed spring meets the margin too (a review: the proposal,
    # n k_min, had broken it), not less than the spring rule's n k_min
    sp = report.summary(analyze(tweak(PAPER, limits__min_jump_speed_ratio=1.6), verify=False))
    proposed = sp["spring_proposal"]["spring_rate_N_per_m"]
    assert proposed == max(k, machine.proposed_rate(1.5, sp["spring_rate_min_N_per_m"]))
    typed = tweak(stiff, dynamics__spring_rate_N_per_m=proposed)
    assert "jump_speed" not in {v.code for v in analyze(typed, verify=False).violations}
    low = tweak(PAPER, limits__min_jump_speed_ratio=1.1)  # the rule's n k_min is more
    sp = report.summary(analyze(low, verify=False))
    assert sp["spring_proposal"]["spring_rate_N_per_m"] == machine.proposed_rate(
        1.5, sp["spring_rate_min_N_per_m"]
    )
    # nothing holds the follower: it leaves at any speed, whatever the margin asks
    loose = tweak(PAPER, limits__min_jump_speed_ratio=1.0, dynamics__spring_rate_N_per_m=0.0)
    loose = tweak(loose, dynamics__gravity_m_s2=0.0, dynamics__preload_mm=0.0)
    (v,) = [v for v in run_all(analyze(loose, verify=False), None) if v.code == "jump_speed"]
    assert "at any speed" in v.message and v.ranges_deg == () and v.amount == 1.0
    # a spring is what helps: no preload without a spring, no lower speed at any speed
    assert "preload (it is 0 N/m)" in v.message and not v.message.endswith("speed")
    with pytest.raises(ValueError, match="min_jump_speed_ratio"):
        tweak(PAPER, limits__min_jump_speed_ratio=0.5)  # below 1 it is no margin


def test_a_rho_range_through_an_inflection_is_said_not_printed():
    """rho passes through infinity where the cam inflects: a signed range across 0 says
    so (a designer's review read "-5148.02 .. 24045.31 mm"); one side prints."""
    from camcore.report import _fmt, rho_range_text

    assert rho_range_text([-5148.02, 24045.31], _fmt).startswith("changes sign")
    assert rho_range_text([56.2, 126.8], _fmt) == "56.20 .. 126.80 mm"
    assert rho_range_text(None, _fmt) == "- mm"


def test_the_jump_speed_check_and_the_summary_share_one_spring_search(monkeypatch):
    """With limits.min_jump_speed_ratio set, the check's spring search is the one the
    summary reports (not searched again), and its figures are machine.spring's."""
    d = tweak(PAPER, limits__min_jump_speed_ratio=1.6)
    direct = machine.spring(d, analyze(d, verify=False).theta)
    calls = []
    monkeypatch.setattr(machine, "spring", lambda *a: calls.append(1) or direct)
    a = analyze(d, verify=False)
    s = report.summary(a)
    assert len(calls) == 1 and "jump_speed" in [v.code for v in a.violations]
    assert s["jump_speed_rpm"] == direct.jump_speed_rpm
    assert s["spring_rate_min_N_per_m"] == direct.rate_min


def test_an_external_load_acts_as_weight_does():
    """dynamics.external_load_N (beyond the paper: a process force toward the cam) adds
    to F_t of Eq. 29 as M g does. Independently: the paper's dwell force by hand,
    F_N = M g + F_e + k (h + s_p) for a single follower; and a design with F_e equals
    one whose gravity carries it (g' = g + F_e / M) in every figure: the forces, the
    stress, the spring, the jump speed, the torque and the elastic train."""
    from camcore.forces import moving_mass
    from camcore.report import summary

    base = load_preset("paper_example").with_kind("single_concave")
    data = base.model_dump()
    data["dynamics"]["external_load_N"] = 50.0
    loaded = Design.model_validate(data)
    s0, s1 = summary(analyze(base, verify=False)), summary(analyze(loaded, verify=False))
    d = base.dynamics
    by_hand = d.mass_g * 1e-3 * d.gravity_m_s2 + d.spring_rate_N_per_m * (15 + 5) * 1e-3
    assert s0["contact_force_max_N"]["high_dwell"] == pytest.approx(by_hand, rel=1e-9)
    assert s1["contact_force_max_N"]["high_dwell"] == pytest.approx(by_hand + 50.0, rel=1e-9)
    assert s1["jump_speed_rpm"] > s0["jump_speed_rpm"]  # it holds the follower on
    # the same load as weight: g' = g + F_e / M, F_e = 0
    data["dynamics"]["external_load_N"] = 0.0
    data["dynamics"]["gravity_m_s2"] = d.gravity_m_s2 + 50.0 / moving_mass(base)
    data["dynamics"]["train_stiffness_N_per_m"] = 2e6  # the elastic train too
    as_weight = summary(analyze(Design.model_validate(data), verify=False))
    data["dynamics"].update(gravity_m_s2=d.gravity_m_s2, external_load_N=50.0)
    with_load = summary(analyze(Design.model_validate(data), verify=False))
    for key in (
        "contact_force_max_N",
        "guide_force_max_N",
        "contact_stress_max_MPa",
        "spring_rate_min_N_per_m",
        "preload_min_mm",
        "jump_speed_rpm",
        "cam_torque_max_Nm",
        "flywheel_energy_J",
        "train",
    ):
        assert with_load[key] == pytest.approx(as_weight[key], rel=1e-9), key
    # pulling it off: a negative load the spring cannot beat at the dwell jumps
    data["dynamics"].update(external_load_N=-1000.0, train_stiffness_N_per_m=None)
    pulled = analyze(Design.model_validate(data), verify=False)
    assert "jump" in {v.code for v in pulled.violations}
    # ... and one just past the weight and the preload's force, where S = 0: off the
    # cam at any speed, not a finite jump speed from the deceleration alone (a review)
    M, k = moving_mass(base), d.spring_rate_N_per_m
    data["dynamics"]["external_load_N"] = -(M * d.gravity_m_s2 + k * d.preload_mm * 1e-3) - 1.0
    s = summary(analyze(Design.model_validate(data), verify=False))
    assert s["jump_speed_rpm"] == 0.0
    assert s["jump_margin"]["jump_speed"] == 0.0
    assert "none: the follower leaves the cam at any speed" in report.report_text(s)


def test_the_reports_inputs_name_what_the_figures_depend_on():
    """A designer's review: the report's inputs said "M 800 g" while the jump speed
    came from M + m_s / 3 = 820 g, and named neither the spring's mass nor the
    elastic train: its inputs could not reproduce its own key numbers."""
    from camcore.model import Design
    from camcore.report import inputs_text

    data = load_preset("paper_example").model_dump()
    data["dynamics"].update(spring_mass_g=60.0, train_stiffness_N_per_m=2e5, damping_ratio=0.07)
    line = next(ln for ln in inputs_text(Design.model_validate(data)).splitlines() if "M " in ln)
    assert "spring mass 60 g" in line and "train k1 200000 N/m zeta 0.07" in line
    assert "g 9.81 m/s2" in line
    plain = inputs_text(load_preset("paper_example"))
    assert "spring mass" not in plain and "train" not in plain  # (none: not said)


def test_the_spring_proposal_says_when_the_jump_margin_sets_it():
    """A designer's review: with a min jump-speed ratio of 1.3 the key numbers read
    "(preload 10 mm, safety factor 1.5)" beside a proposal of 2.06 k_min: the margin,
    not the safety factor, had set it."""
    from camcore.analysis import analyze
    from camcore.model import Design
    from camcore.report import machine_rows, summary

    def line(ratio):
        data = load_preset("paper_example").model_dump()
        data["limits"]["min_jump_speed_ratio"] = ratio
        s = summary(analyze(Design.model_validate(data), verify=False))
        (text,) = [v for k, v in machine_rows(s) if k.startswith("spring rate min")]
        k_min, n = s["spring_rate_min_N_per_m"], s["spring_proposal"]["safety_factor"]
        return text, s["spring_proposal"]["spring_rate_N_per_m"] / (n * k_min)

    text, over = line(1.3)
    assert over > 1.01 and "the rate the min jump-speed ratio asks" in text
    text, over = line(None)
    assert over < 1.01 and "min jump-speed ratio" not in text and "safety factor 1.5" in text


def test_a_contact_force_of_exactly_zero_is_contact_kept_by_every_figure():
    """A dynamics review: a horizontal follower (g = 0) without preload rests on the low
    dwell at F_t = 0. The check called that a jump ("F_N = 0 N <= 0"), while preload_min
    said 0 mm is enough, the jump speed was 1.31x the running speed, and the proposed
    spring failed the same check. F_N = 0 is contact kept, in every figure."""
    d = tweak(PAPER, dynamics__gravity_m_s2=0.0, dynamics__preload_mm=0.0)
    a = analyze(d, verify=False)
    rests = a.in_contact.any(axis=0) & (a.Ft == 0.0)
    assert rests.sum() > 100  # (the low dwell: no load at all)
    s = report.summary(a)
    assert s["preload_min_mm"] == 0.0 and s["jump_margin"]["jump_speed"] > 1.0
    assert a.valid, [v.message for v in a.violations]
    proposed = tweak(d, dynamics__spring_rate_N_per_m=s["spring_proposal"]["spring_rate_N_per_m"])
    assert analyze(proposed, verify=False).valid
    assert jumps(tweak(d, dynamics__spring_rate_N_per_m=s["spring_rate_min_N_per_m"] * 0.98))


def test_an_idle_face_does_not_slide():
    """A review: the idle face of the paper's double concave follower had its
    geometry's sliding speed in the series CSV, and the report's maximum took it (a
    little above any real contact's). A face slides only where it touches."""
    from camcore import wear
    from camcore.report import summary

    a = analyze(PAPER, verify=False)
    v = wear.sliding_speed(a)
    idle = ~a.in_contact
    assert idle.any() and np.all(v[idle] == 0.0)
    touching = wear.sliding_ratio(a) * wear.contact_travel(a, a.geo) * PAPER.cam.speed_rpm * RPM
    assert np.allclose(v[a.in_contact], touching[a.in_contact], rtol=1e-12)
    assert summary(a)["sliding_speed_max_m_per_s"] == float(v[a.in_contact].max())
