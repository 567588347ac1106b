"""The elastic follower train (issue 11): single-DOF steady state checked against the
closed-form response to one harmonic, the rigid limit, and resonance."""

from __future__ import annotations

import math

import numpy as np
import pytest

from camcore import machine, motion, train
from camcore.analysis import analyze
from camcore.model import Design, load_preset
from camcore.units import GRAM, MM, RPM

PAPER = load_preset("paper_example")


def harmonic_cam(speed_rpm: float = 1200.0, **dynamics) -> Design:
    """S = h/2 (1 - cos theta): a simple-harmonic rise over 180 deg and fall over 180
    deg is exactly one harmonic of the cam speed."""
    data = PAPER.model_dump(mode="json")
    data["motion"] = {
        "segments": [
            {"kind": "rise", "angle_deg": 180, "lift_mm": 10, "law": "simple_harmonic"},
            {"kind": "fall", "angle_deg": 180, "lift_mm": 10, "law": "simple_harmonic"},
        ]
    }
    data["limits"]["require_continuous_acceleration"] = False
    data["cam"]["speed_rpm"] = speed_rpm
    data["dynamics"].update(dynamics)
    return Design.model_validate(data)


def test_one_harmonic_matches_the_closed_form():
    """m x'' + c x' + K x = k1 s + c s' - F0 with s = h/2 - h/2 cos(w t): the steady
    state is x = (k1 h/2 - F0)/K - (h/2) Re[G e^{i w t}], G = (k1 + i w c)/(K - m w^2 +
    i w c)."""
    d = harmonic_cam(train_stiffness_N_per_m=2e5, damping_ratio=0.1, spring_mass_g=30.0)
    r = train.respond(d)
    dyn, w = d.dynamics, d.cam.speed_rpm * RPM
    m = (dyn.mass_g + 10.0) * GRAM
    k1, k2 = 2e5, dyn.spring_rate_N_per_m
    K = k1 + k2
    c = 2 * 0.1 * math.sqrt(K * m)
    h = 10 * MM
    F0 = k2 * dyn.preload_mm * MM + m * dyn.gravity_m_s2
    G = (k1 + 1j * w * c) / (K - m * w**2 + 1j * w * c)
    x = (k1 * h / 2 - F0) / K - (h / 2) * np.real(G * np.exp(1j * r.theta))
    np.testing.assert_allclose(r.x, x, atol=1e-9 * h)
    assert r.natural_frequency == pytest.approx(math.sqrt(K / m))
    s = h / 2 * (1 - np.cos(r.theta))
    np.testing.assert_allclose(r.s, s, atol=1e-12)
    Fc = k1 * (s - x) + c * w * (
        h / 2 * np.sin(r.theta) + (h / 2) * np.real(1j * G * np.exp(1j * r.theta))
    )
    np.testing.assert_allclose(r.contact_force, Fc, atol=1e-6 * np.abs(Fc).max())


def test_a_stiff_train_gives_back_the_rigid_model():
    """k1 -> inf: x -> S and F_c -> F_t of Eq. 29 (with the spring's third in the mass)."""
    d = PAPER.model_copy(
        update={"dynamics": PAPER.dynamics.model_copy(update={"train_stiffness_N_per_m": 1e12})}
    )
    r = train.respond(d)
    prog = motion.program(d, r.theta)
    Ft = machine.spring_free_load(d, prog) + machine.spring_force(d, prog)
    np.testing.assert_allclose(r.x, r.s, atol=1e-9)
    np.testing.assert_allclose(r.contact_force, Ft, atol=1e-3 * np.abs(Ft).max())


def test_resonance_shows_when_a_harmonic_meets_the_natural_frequency():
    """With light damping the harmonic cam's tracking error peaks when omega_n equals
    the cam speed (its only harmonic), and is far smaller a little off it."""
    rpm = 6000.0  # fast enough that m w^2 exceeds the return spring's rate
    w = rpm * RPM
    m, k2 = PAPER.dynamics.mass_g * GRAM, PAPER.dynamics.spring_rate_N_per_m

    def error(ratio):
        k1 = m * (ratio * w) ** 2 - k2
        r = train.respond(harmonic_cam(rpm, train_stiffness_N_per_m=k1, damping_ratio=0.02))
        return np.abs(r.x - r.s).max()

    assert error(1.0) > 10 * error(1.5)
    assert error(1.0) > 10 * error(3.0)


def test_an_undamped_train_at_exact_resonance_jumps_and_reports_no_nan():
    """A dynamics review: with zeta = 0 and omega_n exactly on harmonic 10 of the cam
    speed, x and F_c were nan, the JSON held the bare token NaN, and the design passed
    (nan <= 0 is false); a k_1 one part in 10^9 away gave F_c = -5.8e6 N and a jump.
    An undamped train on a harmonic has no steady state: a dynamic jump, no figures."""
    import json

    from camcore.export import series_csv_text
    from camcore.forces import moving_mass
    from camcore.model import omega_rad_s
    from camcore.report import report_text, summary

    m = moving_mass(PAPER)
    k1 = m * (10 * omega_rad_s(PAPER)) ** 2 - PAPER.dynamics.spring_rate_N_per_m
    d = PAPER.model_copy(
        update={
            "dynamics": PAPER.dynamics.model_copy(
                update={"train_stiffness_N_per_m": k1, "damping_ratio": 0.0}
            )
        }
    )
    r = train.respond(d)
    assert r.resonance == 10
    a = analyze(d, verify=False)
    s = summary(a)
    assert not s["valid"] and "dynamic_jump" in [v["code"] for v in s["violations"]]
    assert s["train"]["resonant_harmonic"] == 10 and s["train"]["contact_force_min_N"] is None
    json.dumps(s, allow_nan=False)  # (raises on a nan or an infinity anywhere)
    assert "resonant, no steady state" in report_text(s, d)
    assert "Fc_train_N" not in series_csv_text(a).splitlines()[0]
    near = d.model_copy(update={"dynamics": d.dynamics.model_copy(update={"damping_ratio": 1e-3})})
    assert train.respond(near).resonance == 0
    assert "dynamic_jump" in [v.code for v in analyze(near, verify=False).violations]


def test_dynamic_jump_and_report():
    """A soft train at the paper's speed: the summary gives the natural frequency, the
    error, the residual vibration after each rise and fall, and the dynamic jump."""
    from camcore.report import summary

    soft = PAPER.model_copy(
        update={
            "dynamics": PAPER.dynamics.model_copy(
                update={"train_stiffness_N_per_m": 2e4, "damping_ratio": 0.02}
            )
        }
    )
    s = summary(analyze(soft, verify=False))["train"]
    assert s["natural_frequency_Hz"] == pytest.approx(
        math.sqrt((2e4 + PAPER.dynamics.spring_rate_N_per_m) / (0.108)) / (2 * math.pi)
    )
    assert len(s["residual_vibration"]) == 2  # after the rise and after the fall
    assert s["error_max_mm"] > 0
    # it jumps, and says where: the violation and the summary agree
    a = analyze(soft, verify=False)
    assert s["contact_force_min_N"] < 0 and s["dynamic_jump_deg"]
    assert "dynamic_jump" in {v.code for v in a.violations}
    # a stiffer train rings less after the rise, and does not jump
    stiff = soft.model_copy(
        update={"dynamics": soft.dynamics.model_copy(update={"train_stiffness_N_per_m": 1e6})}
    )
    t = summary(analyze(stiff, verify=False))["train"]
    assert (
        t["residual_vibration"][0]["amplitude_mm"] < s["residual_vibration"][0]["amplitude_mm"] / 10
    )
    assert not t["dynamic_jump_deg"]
    assert summary(analyze(PAPER, verify=False))["train"] is None


def test_contact_force_between_the_samples_is_the_harmonic_sum():
    """The fine contact force (zero-padded spectrum) equals the closed-form one-harmonic
    F_c at angles between the solver's samples, so the dynamic-jump verdict does not
    depend on where the samples fall."""
    d = harmonic_cam(train_stiffness_N_per_m=2e5, damping_ratio=0.1)
    r = train.respond(d)
    theta, Fc = train.contact_force_fine(r)
    assert theta.size == 8 * r.theta.size
    dyn, w = d.dynamics, d.cam.speed_rpm * RPM
    m, k1 = dyn.mass_g * GRAM, 2e5
    K = k1 + dyn.spring_rate_N_per_m
    c = 2 * 0.1 * math.sqrt(K * m)
    h = 10 * MM
    G = (k1 + 1j * w * c) / (K - m * w**2 + 1j * w * c)
    F0 = dyn.spring_rate_N_per_m * dyn.preload_mm * MM + m * dyn.gravity_m_s2
    x = (k1 * h / 2 - F0) / K - (h / 2) * np.real(G * np.exp(1j * theta))
    s = h / 2 * (1 - np.cos(theta))
    ref = k1 * (s - x) + c * w * (
        h / 2 * np.sin(theta) + (h / 2) * np.real(1j * G * np.exp(1j * theta))
    )
    np.testing.assert_allclose(Fc, ref, atol=1e-6 * np.abs(ref).max())


def test_a_harmonic_the_cam_does_not_excite_is_no_resonance():
    """An adversarial review: the double-indexing program repeats every half turn, so
    it has no odd harmonics; an undamped train on harmonic 41 was a "resonance" over the
    whole turn (round-off's |S_41| / |S_2| = 4e-18), and one ulp off it F_c fell to
    -78.5 N. The response there is the lightly damped one's (F_c 24.6 .. 102.6 N)."""
    d = load_preset("double_index")
    k1 = 709950.2759235882  # omega_n = 41 x the cam speed, to the last digit
    assert round(train.natural_frequency(_train(d, k1, 0.0)) / machine.omega_rad_s(d), 9) == 41
    damped = train.respond(_train(d, k1, 1e-6))
    for k in (k1, np.nextafter(k1, 1e9)):
        r = train.respond(_train(d, k, 0.0))
        assert r.resonance == 0
        assert r.contact_force.min() == pytest.approx(damped.contact_force.min(), rel=1e-4)
        assert r.contact_force.max() == pytest.approx(damped.contact_force.max(), rel=1e-4)


def _train(design: Design, k1: float, zeta: float) -> Design:
    dyn = design.dynamics.model_copy(update={"train_stiffness_N_per_m": k1, "damping_ratio": zeta})
    return design.model_copy(update={"dynamics": dyn})
