import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from controller.tactile.field import VectorField, grid_axes_mm
from controller.tactile.nhhd import NHHD, CurlFreePart, greens_self_term
from tests.controller.tactile.fields import GRID_X, GRID_Y, X_MM, Y_MM, source

nhhd = NHHD(X_MM, Y_MM)


def direct_potential(source_values: np.ndarray, x_mm: np.ndarray, y_mm: np.ndarray) -> np.ndarray:
    """O(N^2) reference: D(x_i) = sum_j G(x_i - x_j) s_j dA, G = ln r / 2pi, with the cell
    mean of G on the diagonal (the same regularisation as the FFT version)."""
    gx, gy = np.meshgrid(x_mm, y_mm)
    px, py, s = gx.ravel(), gy.ravel(), source_values.ravel()
    dx, dy = x_mm[1] - x_mm[0], y_mm[1] - y_mm[0]
    self_term = greens_self_term(dx, dy)
    out = np.empty_like(s)
    for i in range(s.size):
        r = np.hypot(px - px[i], py - py[i])
        g = np.empty_like(r)
        nonzero = r > 0
        g[nonzero] = np.log(r[nonzero]) / (2 * np.pi)
        g[~nonzero] = self_term
        out[i] = (g * s).sum() * dx * dy
    return out.reshape(source_values.shape)


def random_field(seed: int, shape=GRID_X.shape):
    rng = np.random.default_rng(seed)
    return rng.normal(size=shape), rng.normal(size=shape)


@pytest.mark.parametrize("cols,rows", [(16, 12), (12, 9), (7, 11)])
def test_fft_potentials_match_direct_sum(cols, rows):
    x, y = grid_axes_mm(320, 240, cols, rows, 0.0634)
    decomposer = NHHD(x, y)
    u, v = random_field(cols * rows, (rows, cols))
    result = decomposer.decompose(u, v)
    for potential, src in ((result.potential_d, result.div), (result.potential_r, result.curl)):
        reference = direct_potential(src, x, y)
        scale = np.abs(reference).max()
        np.testing.assert_allclose(potential, reference, rtol=0, atol=1e-9 * scale)


def test_parts_reconstruct_the_field():
    u, v = random_field(1)
    r = nhhd.decompose(u, v)
    np.testing.assert_allclose(r.d_u + r.r_u + r.h_u, u, atol=1e-12)
    np.testing.assert_allclose(r.d_v + r.r_v + r.h_v, v, atol=1e-12)


def test_curl_free_part_is_curl_free_and_rotational_part_is_divergence_free():
    u, v = random_field(2)
    r = nhhd.decompose(u, v)
    field = VectorField(X_MM, Y_MM, u, v)
    d_curl = VectorField(X_MM, Y_MM, r.d_u.copy(), r.d_v.copy()).curl()
    r_div = VectorField(X_MM, Y_MM, r.r_u.copy(), r.r_v.copy()).divergence()
    # Central differences commute in the interior, so there the identities hold to rounding;
    # the one-sided border differences leave a discretisation error on the outer ring.
    scale = np.abs(field.curl()).max()
    assert np.abs(d_curl[1:-1, 1:-1]).max() < 1e-12 * scale
    assert np.abs(r_div[1:-1, 1:-1]).max() < 1e-12 * scale


def test_rotation_goes_to_the_rotational_part_with_positive_tau_z():
    omega = 0.01
    centre_x, centre_y = X_MM[9], Y_MM[5]  # a grid point away from the centre
    patch = np.exp(-((GRID_X - centre_x) ** 2 + (GRID_Y - centre_y) ** 2) / (2 * 2.0**2))
    u, v = -omega * (GRID_Y - centre_y) * patch, omega * (GRID_X - centre_x) * patch
    r = nhhd.decompose(u, v)
    assert r.tau_z > 0
    assert r.rotation_centre_mm == pytest.approx((centre_x, centre_y))
    assert np.abs(r.d_u).max() < 0.05 * np.abs(r.r_u).max()
    assert nhhd.decompose(-u, -v).tau_z == pytest.approx(-r.tau_z)


def test_an_off_centre_rotation_has_nearly_the_same_torque_about_either_origin():
    centre_x, centre_y = X_MM[9], Y_MM[5]
    patch = np.exp(-((GRID_X - centre_x) ** 2 + (GRID_Y - centre_y) ** 2) / (2 * 2.0**2))
    u, v = -0.01 * (GRID_Y - centre_y) * patch, 0.01 * (GRID_X - centre_x) * patch
    about_gel = nhhd.decompose(u, v).tau_z
    about_rotation = NHHD(X_MM, Y_MM, "rotation_centre").decompose(u, v).tau_z
    # A local rotation carries no net rotational flow, so moving the origin changes little.
    assert about_gel == pytest.approx(about_rotation, rel=0.1)


def test_tilt_keystone_gives_no_torque_about_the_gel_centre():
    """Indentation growing along y magnifies the image more there, u = (x, y) a y / D: its
    curl, -a x / D, is odd in x, so it has no torque about the gel centre; about the
    rotational potential's extremum, off to one side, it does."""
    a = 0.002
    u, v = a * GRID_X * GRID_Y, a * GRID_Y * GRID_Y
    about_gel = nhhd.decompose(u, v).tau_z
    about_rotation = NHHD(X_MM, Y_MM, "rotation_centre").decompose(u, v).tau_z
    assert abs(about_gel) < 1e-12
    assert abs(about_rotation) > 1e-3


def test_unknown_torque_origin_raises():
    with pytest.raises(ValueError, match="tau_z_about"):
        NHHD(X_MM, Y_MM, "somewhere")


def test_expansion_goes_to_the_diverging_part_with_positive_normal():
    u, v = source(X_MM[6], Y_MM[6], q=0.05)
    r = nhhd.decompose(u, v)
    assert r.normal > 0
    assert r.source_centre_mm == pytest.approx((X_MM[6], Y_MM[6]))
    # The source's tail is cut by the grid border, which leaves a little discrete curl.
    assert abs(r.tau_z) < 1e-2 * abs(r.normal)
    assert nhhd.decompose(-u, -v).normal == pytest.approx(-r.normal)


def test_uniform_translation_is_pure_shear():
    u, v = np.full(GRID_X.shape, 0.2), np.full(GRID_X.shape, -0.1)
    r = nhhd.decompose(u, v)
    assert (r.shear_x, r.shear_y) == pytest.approx((0.2, -0.1))
    assert r.tau_z == pytest.approx(0.0, abs=1e-12)
    assert r.normal == pytest.approx(0.0, abs=1e-12)


def test_zero_field_gives_zeros_without_warnings():
    r = nhhd.decompose(np.zeros(GRID_X.shape), np.zeros(GRID_X.shape))
    assert (r.tau_z, r.shear_x, r.shear_y, r.normal) == (0.0, 0.0, 0.0, 0.0)


def test_nan_field_raises():
    u = np.zeros(GRID_X.shape)
    u[2, 2] = np.nan
    with pytest.raises(ValueError, match="NaN or inf"):
        nhhd.decompose(u, np.zeros(GRID_X.shape))


def test_wrong_shape_raises():
    with pytest.raises(ValueError, match="shape"):
        nhhd.decompose(np.zeros((3, 3)), np.zeros((3, 3)))


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 10_000), scale=st.floats(0.01, 100.0))
def test_decomposition_is_linear(seed, scale):
    u, v = random_field(seed)
    a = nhhd.decompose(u, v)
    parts = [p.copy() for p in (a.d_u, a.r_v, a.h_u)]
    b = nhhd.decompose(scale * u, scale * v)
    for before, after in zip(parts, (b.d_u, b.r_v, b.h_u), strict=True):
        np.testing.assert_allclose(after, scale * before, rtol=1e-9, atol=1e-12 * scale)


def test_self_term_matches_a_finer_quadrature():
    a = 1.27
    n = 2000
    s = (np.arange(n) + 0.5) / n - 0.5
    gx, gy = np.meshgrid(s * a, s * a)
    expected = np.log(np.hypot(gx, gy)).mean() / (2 * np.pi)
    assert greens_self_term(a, a) == pytest.approx(expected, rel=1e-4)


@pytest.mark.parametrize("cols,rows", [(16, 12), (8, 6), (7, 11)])
def test_curl_free_part_alone_matches_the_decomposition(cols, rows):
    x_mm, y_mm = grid_axes_mm(320, 240, cols, rows, 0.0634)
    u, v = random_field(cols * rows, (rows, cols))
    whole = NHHD(x_mm, y_mm).decompose(u, v)
    d_u, d_v = CurlFreePart(x_mm, y_mm)(u, v)
    scale = np.abs(whole.d_u).max()
    assert np.abs(d_u - whole.d_u).max() < 1e-10 * scale
    assert np.abs(d_v - whole.d_v).max() < 1e-10 * scale
