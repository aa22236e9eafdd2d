"""Regularised Lucas-Kanade on the grid (controller/tactile/grid_lk.py)."""

from dataclasses import replace

import cv2
import numpy as np
import pytest
from scipy import sparse

from controller.tactile.grid_lk import (
    GridLKFlow,
    grid_laplacian,
    grid_prior,
    normal_matrix,
    pixel_grid,
)
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


def test_normal_matrix_is_the_block_diagonal_plus_the_weighted_prior():
    """Built as a block-sparse matrix, it is entry for entry (structure included, so the
    factorisation is the same) what ``sparse.block_diag`` of the blocks plus the prior gave."""
    blocks = np.random.default_rng(4).normal(size=(ROWS * COLS, 2, 2))
    blocks[7, 0, 1] = blocks[7, 1, 0] = 0.0  # an explicit zero stays explicit
    prior = sparse.kron(grid_laplacian(ROWS, COLS), sparse.identity(2), format="csr")
    expected = (sparse.block_diag(list(blocks), format="csr") + 0.37 * prior).tocsc()
    built = normal_matrix(blocks, 0.37, ROWS, COLS).tocsc()
    np.testing.assert_array_equal(built.indptr, expected.indptr)
    np.testing.assert_array_equal(built.indices, expected.indices)
    np.testing.assert_array_equal(built.data, expected.data)


def test_grid_constants_are_shared_read_only_and_the_direct_constructions():
    grid = pixel_grid(240, 320)
    assert pixel_grid(240, 320) is grid and not grid.flags.writeable
    ys, xs = np.mgrid[0:240, 0:320].astype(np.float32)
    np.testing.assert_array_equal(grid, np.stack([xs, ys], axis=2))
    assert grid_prior(ROWS, COLS) is grid_prior(ROWS, COLS)


def test_the_warp_samples_as_with_one_map_per_axis(renderer):
    """The warp back uses one two-channel map: OpenCV samples the same positions, bit for
    bit, as with the x and y maps apart (the estimates do not change)."""
    reference = renderer.render(None)
    flow = _flow(reference=reference)
    flow._theta[:] = np.random.default_rng(5).normal(0.0, 1.5, flow._theta.shape)
    current = flow._prepare(renderer.render(_translation(0.7, -0.4)), flow._current)
    warped = flow._warp_back(current).copy()
    field = flow._theta.reshape(ROWS, COLS, 2).astype(np.float32)
    dense = cv2.resize(field, (320, 240), interpolation=cv2.INTER_LINEAR)
    ys, xs = np.mgrid[0:240, 0:320].astype(np.float32)
    expected = cv2.remap(
        current,
        xs + dense[..., 0],
        ys + dense[..., 1],
        cv2.INTER_LINEAR,
        borderMode=cv2.BORDER_REPLICATE,
    )
    np.testing.assert_array_equal(warped, expected)
