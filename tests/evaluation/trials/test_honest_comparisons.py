"""The comparison's controllers and scoring: the oracle's units and noise, the
ablations' channels, the blind baseline on an easy setting, and the plug's contact force
against the connector's limit."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from controller.run import CONTROLLERS
from controller.run.controllers import torques_only, zero_torques
from controller.run.task import load_task
from controller.tactile.wrench import WrenchEstimate
from core.config import ConfigError
from evaluation.trials import trial
from evaluation.trials.oracle import TRIAL_CONTROLLERS, TRUE_AXES, TrueWrench, oracle_noise_std
from evaluation.trials.trial import INSERTION_FORCE_EXCEEDED, insertion_force_violations

EASY = (
    "scene.hole_uncertainty.yaw_rad=0.0",
    "scene.hole_uncertainty.x_m=0.0005",
    "scene.hole_uncertainty.y_m=0.0005",
    "blind.half_width_m=0.0005",
    "blind.yaw_range_rad=0.0",
    "blind.pitch_m=0.0001",
)
"""The easy setting the blind baseline is shown to succeed on: a known yaw and +-0.5 mm."""

RAW = WrenchEstimate(1.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, contact=True,
                     degenerate=False, slip_suspected=False, slip_gross=False,
                     rezero_recommended=False, zeroing=False, calibrated=True)  # fmt: skip


def test_zero_torque_zeroes_the_torques_and_keeps_the_forces():
    e = zero_torques(RAW)
    assert (e.tau_x, e.tau_y, e.tau_z) == (0.0, 0.0, 0.0)
    assert (e.shear_x, e.shear_y, e.normal) == (4.0, 5.0, 6.0)
    assert (e.fv_tau_x, e.contact, e.t_s) == (7.0, True, 1.0)


def test_torque_only_zeroes_the_forces_and_keeps_the_torques():
    e = torques_only(RAW)
    assert (e.shear_x, e.shear_y, e.normal) == (0.0, 0.0, 0.0)
    assert (e.tau_x, e.tau_y, e.tau_z) == (1.0, 2.0, 3.0)


def test_the_ablations_are_in_the_product_table_and_the_trial_tools():
    for name in ("zero_torque", "torque_only"):
        assert name in CONTROLLERS and name in TRIAL_CONTROLLERS
        assert not CONTROLLERS[name].sim_only


def test_the_oracle_reports_the_true_wrench_in_calibrated_units_with_noise():
    truth = {"t": np.array([0.5, -0.2, 1.0, 1e-3, -2e-3, 3e-4])}
    noise = np.array([0.01, 0.02, 0.03, 1e-5, 2e-5, 3e-5])
    oracle = TrueWrench(lambda t_s: truth["t"], noise, np.random.default_rng(0))
    zero = oracle(dataclasses.replace(RAW, zeroing=True))
    assert zero.zeroing and zero.calibrated
    truth["t"] = truth["t"] + np.array([1.0, 2.0, 3.0, 0.01, 0.02, 0.03])  # a load after zeroing
    samples = np.array([[getattr(oracle(RAW), name) for name in TRUE_AXES] for _ in range(4000)])
    expected = np.array([1.0, 2.0, 3.0, 0.01, 0.02, 0.03])  # N, N, N, N*m, N*m, N*m
    assert (np.abs(samples.mean(axis=0) - expected) <= 4 * noise / np.sqrt(4000)).all()
    np.testing.assert_allclose(samples.std(axis=0), noise, rtol=0.06)
    assert oracle(RAW).calibrated and oracle(RAW).fv_tau_z == RAW.fv_tau_z


def test_the_oracle_noise_is_the_calibrations_measured_noise_at_rest():
    calibration = load_task("usb_c").calibration
    std = oracle_noise_std(calibration)
    assert std.shape == (6,) and (std > 0).all()
    assert std[3] == calibration.axes["tau_x"].rest_std
    assert std[0] == calibration.axes["shear_x"].rest_std
    with pytest.raises(ConfigError, match="names no calibration"):
        oracle_noise_std(None)


def test_violations_count_each_rise_above_the_limit():
    force = np.array([0.0, 25.0, 30.0, 5.0, 21.0, 1.0, 22.0])
    assert insertion_force_violations(force, 20.0) == 3
    assert insertion_force_violations(np.array([21.0, 1.0]), 20.0) == 1
    assert insertion_force_violations(np.array([]), 20.0) == 0


def test_blind_succeeds_on_the_easy_setting_and_a_contact_violation_fails_it():
    outcome = trial.run(load_task("usb_c", EASY), "blind", 0)
    result = outcome.result
    assert result.success and result.failure_reason is None, result
    assert 0 < result.p99_contact_force_n <= result.max_contact_force_n < 20.0
    assert result.contact_force_limit_n == 20.0 and result.insertion_force_violations == 0
    assert result.max_contact_force_n > result.max_wrist_force_n  # the plug's, not the wrist's
    strict = trial.run(load_task("usb_c", [*EASY, "contact_force_limit_n=3.0"]), "blind", 0)
    assert not strict.result.success and strict.result.status == "failed"
    assert strict.result.failure_reason == INSERTION_FORCE_EXCEEDED
    assert strict.result.insertion_force_violations >= 1
