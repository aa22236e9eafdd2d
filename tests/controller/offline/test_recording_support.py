"""The contact's support from a whole recording (controller/offline/recording_support.py)."""

import numpy as np
import pytest

from controller.offline.recording_support import (
    MIN_FRAMES,
    MOTION_SIGNIFICANCE,
    motion_significance,
    recording_support,
)

X_MM = np.arange(16) - 7.5  # cell centres, 1 mm apart
Y_MM = np.arange(12) - 5.5
GRID_X, GRID_Y = np.meshgrid(X_MM, Y_MM)
# a contact over columns 8-13 and rows 2-6: centre (3.0, -1.5) mm, off the gel centre
CONTACT = ((GRID_X > 0) & (GRID_X < 6) & (GRID_Y > -4) & (GRID_Y < 1)).astype(float)
CENTRE = (3.0, -1.5)


def _recording(push: float, tilt: float, noise: float, frames: int = 160, seed: int = 0):
    """Divergences (frames, 12, 16): a press swinging by ``push`` and a tilt about x (a
    gradient along y of ``tilt`` per mm at its peak) on the contact, plus white noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(frames) / frames
    pressure = push * np.sin(2 * np.pi * 1.7 * t + 0.3)
    tilting = np.sin(2 * np.pi * 2.5 * t + 1.1)
    lever = CONTACT * (GRID_Y - CENTRE[1])
    signal = pressure[:, None, None] * CONTACT + tilt * tilting[:, None, None] * lever
    return signal + noise * rng.standard_normal(signal.shape), tilting


def _tilt_x(divergences: np.ndarray, weights: np.ndarray, centre_y: float) -> np.ndarray:
    return (weights * (GRID_Y - centre_y) * divergences).sum(axis=(1, 2))


def test_under_a_swinging_press_the_support_is_the_contact_and_the_push_drops_out():
    divergences, tilting = _recording(push=0.5, tilt=0.05, noise=0.02)
    support = recording_support(divergences, X_MM, Y_MM)
    assert support is not None
    assert support.centre_mm == pytest.approx(CENTRE, abs=0.02)
    assert np.all(support.weights[CONTACT == 0] == 0.0)
    about_support = _tilt_x(divergences, support.weights, support.centre_mm[1])
    about_gel_centre = _tilt_x(divergences, np.ones_like(CONTACT), 0.0)
    assert np.corrcoef(about_support, tilting)[0, 1] > 0.99
    assert np.corrcoef(about_gel_centre, tilting)[0, 1] < 0.5  # the push leaks in


def test_a_weak_tilt_alone_stands_out_of_the_noise_cell_by_cell():
    """The tilt's divergence is at most twice the noise per frame (at the contact's edges)
    and below it near the middle; taken relative to the noise, the support is still on the
    contact, centred on it, and the moment about it follows the tilt better than the whole
    grid's does."""
    divergences, tilting = _recording(push=0.0, tilt=0.02, noise=0.02)
    support = recording_support(divergences, X_MM, Y_MM)
    assert support is not None
    assert support.weights[CONTACT == 0].sum() < 0.01
    assert support.weights[CONTACT == 1].sum() >= 8.0
    assert support.centre_mm == pytest.approx(CENTRE, abs=0.1)
    about_support = _tilt_x(divergences, support.weights, support.centre_mm[1])
    whole_grid = _tilt_x(divergences, np.ones_like(CONTACT), 0.0)
    assert np.corrcoef(about_support, tilting)[0, 1] > 0.97
    assert np.corrcoef(whole_grid, tilting)[0, 1] < 0.8


def test_noise_alone_finds_no_support_though_the_reference_noise_looks_like_a_weak_tilt():
    """Zeroed on a reference of 4 noisy frames, every frame carries that reference's noise, a
    constant per cell. Its power over the recording reaches that of a weak tilt on some cell
    (a support would weigh those cells); its change over the recording does not, and no
    support is taken."""
    divergences, _ = _recording(push=0.0, tilt=0.02, noise=0.02)
    assert motion_significance(divergences, 0.02**2) >= MOTION_SIGNIFICANCE
    assert recording_support(divergences, X_MM, Y_MM) is not None
    for seed in range(10):
        rng = np.random.default_rng(seed)
        reference = 0.01 * rng.standard_normal((12, 16))  # 4 frames averaged: noise / 2
        noise = reference + 0.02 * rng.standard_normal((160, 12, 16))
        power = np.square(noise).mean(axis=0) / 0.02**2 - 1.0
        tilt_power = np.square(divergences).mean(axis=0) / 0.02**2 - 1.0
        assert power.max() > 0.5 * tilt_power.max()
        assert motion_significance(noise, 0.02**2) < 0.5 * MOTION_SIGNIFICANCE
        assert recording_support(noise, X_MM, Y_MM) is None


def test_no_support_without_enough_frames_or_any_noise_or_signal():
    divergences, _ = _recording(push=0.5, tilt=0.05, noise=0.02)
    assert recording_support(divergences[: MIN_FRAMES - 1], X_MM, Y_MM) is None
    still = np.repeat(divergences[:1], 20, axis=0)  # no frame-to-frame change
    assert recording_support(still, X_MM, Y_MM) is None
    assert recording_support(np.zeros((20, 12, 16)), X_MM, Y_MM) is None


def test_bad_divergences_are_refused_naming_what_was_expected():
    with pytest.raises(ValueError, match=r"\(frames, 12, 16\), got \(20, 16, 12\)"):
        recording_support(np.zeros((20, 16, 12)), X_MM, Y_MM)
    bad = np.zeros((20, 12, 16))
    bad[3, 4, 5] = np.nan
    with pytest.raises(ValueError, match="divergences contains NaN"):
        recording_support(bad, X_MM, Y_MM)
