import numpy as np
import pytest

from controller.tactile.field import VectorField, block_mean, grid_axes_mm, require_finite
from tests.controller.tactile.fields import GRID_X, GRID_Y, X_MM, Y_MM


def test_grid_axes_have_half_cell_offset_and_are_centred():
    x, y = grid_axes_mm(320, 240, 16, 12, 0.0634)
    assert x[0] == pytest.approx((10 - 160) * 0.0634)  # centre of the first 20 px cell
    assert x.mean() == pytest.approx(0.0, abs=1e-12)
    assert y.mean() == pytest.approx(0.0, abs=1e-12)
    assert np.diff(x) == pytest.approx(np.full(15, 20 * 0.0634))


def test_grid_too_small_is_rejected():
    with pytest.raises(ValueError, match="at least 3x3"):
        grid_axes_mm(320, 240, 2, 12, 0.0634)


def test_uniform_translation_has_no_divergence_or_curl():
    f = VectorField(X_MM, Y_MM, np.full(GRID_X.shape, 0.3), np.full(GRID_X.shape, -0.2))
    assert np.abs(f.divergence()).max() < 1e-12
    assert np.abs(f.curl()).max() < 1e-12


def test_pure_rotation_gives_curl_and_no_divergence():
    omega = 0.02  # rad, small rigid rotation about the gel centre
    f = VectorField(X_MM, Y_MM, -omega * GRID_Y, omega * GRID_X)
    assert f.curl() == pytest.approx(np.full(GRID_X.shape, 2 * omega))
    assert np.abs(f.divergence()).max() < 1e-12


def test_pure_expansion_gives_divergence_and_no_curl():
    k = 0.01
    f = VectorField(X_MM, Y_MM, k * GRID_X, k * GRID_Y)
    assert f.divergence() == pytest.approx(np.full(GRID_X.shape, 2 * k))
    assert np.abs(f.curl()).max() < 1e-12


def test_derivatives_are_second_order_inside_and_first_order_on_borders():
    u = 0.01 * GRID_X**2
    f = VectorField(X_MM, Y_MM, u, np.zeros_like(u))
    div = f.divergence()
    assert div[:, 1:-1] == pytest.approx(0.02 * GRID_X[:, 1:-1])  # exact for a quadratic
    np.testing.assert_allclose(div, np.gradient(u, X_MM, axis=1, edge_order=1), atol=1e-12)


def test_nan_field_is_named_in_the_error():
    u = np.zeros(GRID_X.shape)
    u[3, 4] = np.nan
    with pytest.raises(ValueError, match="field contains NaN"):
        require_finite("field", u)


def test_shape_mismatch_is_rejected():
    with pytest.raises(ValueError, match="shape"):
        VectorField(X_MM, Y_MM, np.zeros((3, 3)), np.zeros((3, 3)))


def test_block_mean_averages_each_block():
    a = np.arange(24.0).reshape(4, 6)
    out = np.empty((2, 3))
    assert block_mean(a, (2, 2), out) is out
    assert out[0, 0] == pytest.approx((0 + 1 + 6 + 7) / 4)
    assert out[1, 2] == pytest.approx((16 + 17 + 22 + 23) / 4)
    assert np.array_equal(block_mean(a, (1, 1), np.empty((4, 6))), a)
    wide = block_mean(a, (4, 3), np.empty((1, 2)))  # blocks of 4 rows x 3 columns
    assert wide[0, 1] == pytest.approx(np.mean(a[:, 3:]))
