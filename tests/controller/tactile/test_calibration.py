import numpy as np
import pytest

from controller.cli.outputs import write_text
from controller.tactile.calibration import AxisFit, Calibration, fit_axis
from core.config import ConfigError


def series(rng, slope=0.004, offset=0.0, noise=0.0):
    truth_t = np.arange(0, 20, 1 / 62.5)  # F/T at 62.5 Hz
    truth = np.sin(2 * np.pi * truth_t / 5.0) * 0.1
    est_t = np.sort(rng.uniform(0.5, 19.5, 380))  # tactile at ~19 Hz with jitter
    est = (np.interp(est_t, truth_t, truth) - offset) / slope + rng.normal(0, noise, est_t.size)
    return est_t, est, truth_t, truth


def test_recovers_scale_across_different_rates():
    rng = np.random.default_rng(0)
    est_t, est, truth_t, truth = series(rng)
    fit = fit_axis(est_t, est, truth_t, truth)
    assert fit.slope == pytest.approx(0.004, rel=1e-4)
    assert fit.r2 == pytest.approx(1.0, abs=1e-6) and fit.rmse < 1e-4
    assert fit.samples == est_t.size and fit.intercept == 0.0


def test_offset_is_fitted_only_when_asked():
    rng = np.random.default_rng(1)
    est_t, est, truth_t, truth = series(rng, offset=0.02)
    with_offset = fit_axis(est_t, est, truth_t, truth, with_offset=True)
    assert with_offset.intercept == pytest.approx(0.02, rel=1e-3)
    assert with_offset.rmse < fit_axis(est_t, est, truth_t, truth).rmse


def test_noise_lowers_r2_and_raises_rmse():
    rng = np.random.default_rng(2)
    clean = fit_axis(*series(rng))
    noisy = fit_axis(*series(rng, noise=5.0))
    assert noisy.r2 < clean.r2 and noisy.rmse > clean.rmse


def test_samples_outside_the_truth_span_are_dropped():
    rng = np.random.default_rng(3)
    est_t, est, truth_t, truth = series(rng)
    est_t = est_t + 10.0  # half of them now after the truth ends
    fit = fit_axis(est_t, est, truth_t, truth)
    assert fit.samples == int((est_t <= truth_t[-1]).sum())


def test_disjoint_clocks_are_an_error():
    with pytest.raises(ValueError, match="same clock"):
        fit_axis(np.arange(5) + 100.0, np.ones(5), np.arange(5.0), np.ones(5))


def test_nan_input_is_an_error():
    with pytest.raises(ValueError, match="estimate contains NaN"):
        fit_axis(np.arange(5.0), np.array([1, 2, np.nan, 4, 5]), np.arange(5.0), np.ones(5))


def test_save_and_load_round_trip(tmp_path):
    cal = Calibration("gelsight_mini", "default", {"tau_x": AxisFit(0.004, 0.0, 0.001, 0.99, 100)})
    path = tmp_path / "cal.yaml"
    write_text(path, cal.to_yaml())
    assert Calibration.load(path) == cal


@pytest.mark.parametrize(
    "text,message",
    [
        ("format: other\n", "key 'format'"),
        (
            "format: tactile-insertion/calibration/v1\nsensor: s\nestimator: e\n",
            "missing key 'axes'",
        ),
        (
            "format: tactile-insertion/calibration/v1\nsensor: s\nestimator: e\n"
            "axes:\n  tau_q: {}\n",
            "unknown key 'axes.tau_q'",
        ),
        (
            "format: tactile-insertion/calibration/v1\nsensor: s\nestimator: e\naxes:\n"
            "  tau_x: {slope: .nan, intercept: 0, rmse: 0, r2: 1, samples: 3}\n",
            "finite",
        ),
        (
            "format: tactile-insertion/calibration/v2\nsensor: s\nestimator: e\n"
            "estimator_sha256: null\naxes:\n"
            "  tau_x: {slope: true, intercept: 0, rmse: 0, r2: 1, samples: 3}\n",
            "axes.tau_x.slope",
        ),
        (
            "format: tactile-insertion/calibration/v2\nsensor: s\nestimator: e\n"
            "estimator_sha256: null\naxes:\n"
            "  tau_x: {slope: 1, intercept: 0, rmse: 0, r2: 1, samples: 1.5}\n",
            "axes.tau_x.samples",
        ),
        (
            "format: tactile-insertion/calibration/v2\nsensor: s\nestimator: e\n"
            "estimator_sha256: null\naxes: [1, 2]\n",
            "key 'axes': expected a mapping",
        ),
        (
            "format: tactile-insertion/calibration/v2\nsensor: s\nestimator: e\n"
            "estimator_sha256: abc\naxes: {}\n",
            "estimator_sha256",
        ),
        (
            "format: tactile-insertion/calibration/v2\nsensor: s\nestimator: e\naxes: {}\n",
            "missing key 'estimator_sha256'",
        ),
    ],
)
def test_bad_calibration_files_name_the_key(tmp_path, text, message):
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(ConfigError, match=message):
        Calibration.load(path)
