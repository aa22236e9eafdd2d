"""Regularised Lucas-Kanade on the grid (controller/tactile/grid_lk.py)."""

from dataclasses import replace

import numpy as np
import pytest

from controller.tactile.grid_lk import GridLKFlow, grid_laplacian
from controller.tactile.settings import estimator_config
from drivers.sim.render.marker_images import area_mean_field, smooth_random_field

ROWS, COLS = 12, 16
GRID_LK = estimator_config("default").flow


def _flow(config=GRID_LK, reference=None):
    flow = GridLKFlow(config, (240, 320), ROWS, COLS)
    if reference is not None:
        flow.set_reference(reference)
    return flow


def _translation(dx: float, dy: float) -> np.ndarray:
    field = np.zeros((240, 320, 2), np.float32)
    field[..., 0], field[..., 1] = dx, dy
    return field


def test_grid_laplacian_is_the_sum_of_squared_neighbour_differences():
    rows, cols = 3, 4
    laplacian = grid_laplacian(rows, cols).toarray()
    np.testing.assert_array_equal(laplacian, laplacian.T)
    np.testing.assert_array_equal(laplacian.sum(axis=1), 0.0)
    u = np.random.default_rng(0).normal(size=(rows, cols))
    expected = (np.diff(u, axis=0) ** 2).sum() + (np.diff(u, axis=1) ** 2).sum()
    assert u.ravel() @ laplacian @ u.ravel() == pytest.approx(expected)


@pytest.mark.parametrize(
    "change",
    [
        {},
        {"color": "gray"},
        {"scale": 0.5, "grid_lk": replace(GRID_LK.grid_lk, blur_sigma_px=1.5)},
        {"warm_start": False},
        {"grid_lk": replace(GRID_LK.grid_lk, normalize_brightness=False, blur_sigma_px=0.0)},
    ],
    ids=["per_channel", "gray", "half_scale", "cold", "plain"],
)
def test_recovers_a_subpixel_translation(renderer, change):
    flow = _flow(replace(GRID_LK, **change), renderer.render())
    out = flow.measure(renderer.render(_translation(0.3, -0.2)), np.empty((ROWS, COLS, 2)))
    # Every cell within a few hundredths of a px (twice that at half scale, where the sharp
    # markers make each warped Gauss-Newton step's bilinear resampling less exact).
    tolerance = 0.08 if change.get("scale") == 0.5 else 0.04
    np.testing.assert_allclose(out[..., 0], 0.3, atol=tolerance)
    np.testing.assert_allclose(out[..., 1], -0.2, atol=tolerance)


def test_warm_start_converges_to_the_cold_answer(renderer):
    rng = np.random.default_rng(5)
    fields = [smooth_random_field((240, 320), 2.0, rng) for _ in range(2)]
    images = [renderer.render(f) for f in fields]
    reference = renderer.render()
    cold = _flow(replace(GRID_LK, warm_start=False), reference)
    warm = _flow(GRID_LK, reference)
    out = np.empty((ROWS, COLS, 2))
    warm.measure(images[0], out)
    for _ in range(3):  # a held frame: the warm start keeps refining the same answer
        warm_field = warm.measure(images[1], out).copy()
    truth = area_mean_field(fields[1], ROWS, COLS)
    cold_field = cold.measure(images[1], np.empty((ROWS, COLS, 2)))
    assert np.sqrt(((warm_field - truth) ** 2).sum(-1).mean()) < 0.1
    assert np.abs(warm_field - cold_field).max() < 0.1
    # and a new reference forgets the previous frames
    warm.set_reference(reference)
    np.testing.assert_allclose(warm.measure(images[1], out), cold_field, atol=1e-9)


def test_brightness_normalisation_ignores_a_drifting_light(renderer):
    reference = renderer.render()
    y, x = np.mgrid[0:240, 0:320]
    gain = 1.0 + 0.03 * np.stack([x / 320, 1 - y / 240, np.ones_like(x)], axis=-1)
    relit = np.clip(reference * gain + 4.0, 0, 255).astype(np.uint8)
    out = np.empty((ROWS, COLS, 2))
    normalised = _flow(reference=reference).measure(relit, out).copy()
    plain_config = replace(GRID_LK, grid_lk=replace(GRID_LK.grid_lk, normalize_brightness=False))
    plain = _flow(plain_config, reference).measure(relit, out)
    assert np.abs(normalised).max() < 0.05
    assert np.abs(plain).max() > 2 * np.abs(normalised).max()


def test_featureless_image_gives_a_zero_finite_field():
    flat = np.full((240, 320, 3), 120, np.uint8)
    out = _flow(reference=flat).measure(flat, np.full((ROWS, COLS, 2), np.nan))
    assert np.isfinite(out).all() and np.abs(out).max() < 1e-9


def test_rejects_another_method():
    with pytest.raises(ValueError, match="grid_lk"):
        GridLKFlow(replace(GRID_LK, method="dis"), (240, 320), ROWS, COLS)
