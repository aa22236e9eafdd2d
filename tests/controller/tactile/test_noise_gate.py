"""The no-contact gate (controller/tactile/noise_gate.py), the grid LK's noise propagation
(GridLKFlow.noise_covariance) and the gate in the estimator."""

from dataclasses import replace

import cv2
import numpy as np
import pytest
from scipy.stats import chi2

from controller.tactile.estimator import TactileEstimator
from controller.tactile.grid_lk import GridLKFlow
from controller.tactile.noise_gate import NoiseGate
from controller.tactile.settings import estimator_config
from core.sensor_profile import sensor_profile

PROFILE = sensor_profile("gelsight_mini")
DEFAULT = estimator_config("default")


def _covariance(k: int, rank: int, seed: int = 0) -> np.ndarray:
    factor = np.random.default_rng(seed).normal(size=(k, rank))
    return factor @ factor.T


def test_noise_alone_opens_the_gate_on_about_the_false_alarm_share():
    covariance = _covariance(16, 12)
    gate = NoiseGate(covariance, false_alarm=0.05)
    assert gate.rank == 12
    assert gate.threshold == pytest.approx(chi2.isf(0.05, 12))
    draws = np.random.default_rng(1).multivariate_normal(np.zeros(16), covariance, 4000)
    opened = np.mean([gate(d) > 0.0 for d in draws])
    assert 0.035 < opened < 0.065


def test_a_field_well_above_the_noise_passes_unchanged_and_the_gate_is_continuous():
    covariance = _covariance(16, 12)
    gate = NoiseGate(covariance, false_alarm=1e-3)
    direction = covariance @ np.random.default_rng(2).normal(size=16)
    unit = direction / np.sqrt(gate.statistic(direction))  # statistic 1
    scales = np.linspace(0.0, 2.0 * np.sqrt(gate.threshold) * 1.1, 400)
    values = np.array([gate(s * unit) for s in scales])
    assert values[0] == 0.0 and values[-1] == 1.0
    assert np.all(np.diff(values) >= 0.0)  # monotone along a ray
    # Lipschitz in the statistic: slope of smoothstep / threshold at most 1.5 / threshold.
    statistic = scales**2
    assert np.max(np.diff(values) / np.diff(statistic)) <= 1.5 / gate.threshold + 1e-9


def test_the_gate_stays_open_once_a_contact_is_established():
    covariance = _covariance(16, 12)
    gate = NoiseGate(covariance, false_alarm=0.01)
    draws = np.random.default_rng(3).multivariate_normal(np.zeros(16), covariance, 2000)
    assert [gate.until_contact(d) for d in draws] == [gate(d) for d in draws]
    assert not gate.contact  # noise alone: no run of three frames above the threshold
    direction = covariance @ np.random.default_rng(4).normal(size=16)
    unit = direction / np.sqrt(gate.statistic(direction))
    q = gate.threshold
    weak = np.sqrt(1.2 * q) * unit  # above the threshold, gate partly open
    assert 0.0 < gate(weak) < 1.0
    assert gate.until_contact(weak) == gate(weak) and gate.until_contact(weak) == gate(weak)
    assert gate.until_contact(0.0 * unit) == 0.0  # the run is broken
    assert [gate.until_contact(weak) for _ in range(3)] == [gate(weak), gate(weak), 1.0]
    assert gate.contact and gate.until_contact(0.0 * unit) == 1.0  # latched
    assert gate.peak == pytest.approx(max(gate.statistic(d) for d in [*draws, weak]) / q)
    gate.until_contact(3.0 * weak)  # the peak is kept after the latch too
    assert gate.peak == pytest.approx(9.0 * 1.2)
    once = NoiseGate(covariance, false_alarm=0.01)
    assert once.until_contact(2.0 * weak) == 1.0 and once.until_contact(0.0 * unit) == 1.0


def test_bad_gates_are_refused():
    with pytest.raises(ValueError, match="false_alarm"):
        NoiseGate(np.eye(3), 0.0)
    with pytest.raises(ValueError, match="zero"):
        NoiseGate(np.zeros((3, 3)), 0.01)


def _markerless_gel(rng: np.random.Generator) -> np.ndarray:
    """A markerless gel's look (float BGR, 240 x 320): smooth coloured shading and a fine
    texture of a few grey levels, as the real backgrounds (drivers/sim/render/real_gels)."""
    ys, xs = np.mgrid[0:240, 0:320] / 320.0
    shading = np.stack([120 + 60 * xs, 110 + 50 * ys, 130 - 40 * xs * ys], axis=-1)
    fine = cv2.GaussianBlur(rng.normal(0.0, 8.0, (240, 320, 3)), (0, 0), 1.2)
    return shading + fine


@pytest.mark.parametrize("color", ["per_channel", "gray"])
def test_the_propagated_noise_matches_monte_carlo(color):
    """On a markerless texture (the model's premise: gradients over the whole cell; on
    sharp markers over a flat gel the noise is underestimated, docs/ARCHITECTURE.md)."""
    flow_config = replace(DEFAULT.flow, color=color)
    rows, cols = 12, 16
    flow = GridLKFlow(flow_config, (240, 320), rows, cols)
    rng = np.random.default_rng(4)
    clean = _markerless_gel(rng)
    noise_grey = 3.0

    def noisy() -> np.ndarray:
        return np.clip(np.rint(clean + rng.normal(0.0, noise_grey, clean.shape)), 0, 255).astype(
            np.uint8
        )

    operator = rng.normal(size=(3, 2 * rows * cols))
    samples = []
    for _ in range(30):  # each draw: a new noisy reference and a new noisy frame
        flow.set_reference(noisy())
        samples.append(operator @ flow.measure(noisy(), np.empty((rows, cols, 2))).ravel())
    measured = np.var(samples, axis=0)
    predicted = np.diag(flow.noise_covariance(noise_grey, operator))
    np.testing.assert_allclose(measured / predicted, 1.0, atol=0.5)


def _frame(gel: np.ndarray, rng: np.random.Generator, field_px: np.ndarray | None = None):
    """``gel`` moved by ``field_px`` (backward map, enough for small fields), with 2 grey
    levels of camera noise, as uint8."""
    image = gel
    if field_px is not None:
        ys, xs = np.mgrid[0:240, 0:320].astype(np.float32)
        map_x, map_y = (
            xs - field_px[..., 0].astype(np.float32),
            ys - field_px[..., 1].astype(np.float32),
        )
        image = cv2.remap(gel.astype(np.float32), map_x, map_y, cv2.INTER_CUBIC)
    noisy = image + rng.normal(0.0, 2.0, image.shape)
    return np.clip(np.rint(noisy), 0, 255).astype(np.uint8)


def _press_and_tilt_px(press: float, tilt: float) -> np.ndarray:
    """A centred bulge whose spread rises toward +y by ``tilt``: px."""
    ys, xs = np.mgrid[0:240, 0:320].astype(float)
    dx, dy = xs - 160.0, ys - 120.0
    k = (press + tilt * dy / 60.0) / 30.0 * np.exp(-(dx**2 + dy**2) / (2 * 40.0**2))
    return np.stack([k * dx, k * dy], axis=-1)


def test_zeroed_on_the_open_gel_the_tilt_is_zero_until_contact():
    rng = np.random.default_rng(5)
    gel = _markerless_gel(rng)
    gated = TactileEstimator(DEFAULT, PROFILE)
    plain = TactileEstimator(replace(DEFAULT, noise_gate=None), PROFILE)
    reference = _frame(gel, rng)
    for est in (gated, plain):
        est.set_reference(reference)
    for frame in [_frame(gel, rng) for _ in range(5)]:
        a, b = gated.push(frame, 0.0), plain.push(frame, 0.0)
        assert (a.tau_x, a.tau_y) == (0.0, 0.0) and a.degenerate
        assert (b.tau_x, b.tau_y) != (0.0, 0.0)
        assert (a.tau_z, a.shear_x, a.normal) == (b.tau_z, b.shear_x, b.normal)  # tilt only
    pressed = _frame(gel, rng, _press_and_tilt_px(1.0, 0.3))
    a, b = gated.push(pressed, 0.1), plain.push(pressed, 0.1)
    assert (a.tau_x, a.tau_y) == (b.tau_x, b.tau_y) and a.tau_x > 0.0


def test_with_the_grasps_contact_there_is_no_gate(renderer):
    est = TactileEstimator(DEFAULT, PROFILE)
    est.set_open_reference(renderer.render())
    est.set_reference(renderer.render(_press_and_tilt_px(1.0, 0.0)))
    assert est.contact_centre_mm is not None and not est.noise_gated
    est = TactileEstimator(DEFAULT, PROFILE)
    est.set_reference(renderer.render())
    assert est.noise_gated


def test_other_flows_form_no_gate(renderer):
    config = replace(DEFAULT, flow=replace(DEFAULT.flow, method="dis"))
    est = TactileEstimator(config, PROFILE)
    est.set_reference(renderer.render())
    assert not est.noise_gated


def test_a_featureless_reference_forms_no_gate():
    est = TactileEstimator(DEFAULT, PROFILE)
    est.set_reference(np.full((240, 320, 3), 128, np.uint8))
    assert not est.noise_gated
    estimate = est.push(np.full((240, 320, 3), 128, np.uint8), 0.0)
    assert (estimate.tau_x, estimate.tau_y) == (0.0, 0.0)
