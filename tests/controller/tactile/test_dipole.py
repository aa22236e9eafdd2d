import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from controller.tactile.dipole import DipoleMomentCalculator
from controller.tactile.field import VectorField
from tests.controller.tactile.fields import GRID_X, X_MM, Y_MM, charge_on, charge_pair, source

dipole = DipoleMomentCalculator(X_MM, Y_MM)


def div_of(u, v):
    return VectorField(X_MM, Y_MM, u, v).divergence()


@pytest.mark.parametrize("axis", ["x", "y"])
@pytest.mark.parametrize("sign", [1, -1])
def test_opposite_charges_give_a_dipole_along_their_axis(axis, sign):
    u, v = charge_pair(axis, separation=5.0, q=sign * 0.05)
    d = dipole(div_of(u, v))
    along, across = (d.p_x, d.p_y) if axis == "x" else (d.p_y, d.p_x)
    assert np.sign(along) == sign  # points from the negative to the positive charge
    assert abs(across) < 1e-3 * abs(along)
    tau_x, tau_y = d.tilt_torque_raw
    if axis == "y":  # more pressure toward +y: positive torque about x
        assert np.sign(tau_x) == sign and abs(tau_y) < 1e-3 * abs(tau_x)
    else:  # more pressure toward +x: negative torque about y
        assert np.sign(tau_y) == -sign and abs(tau_x) < 1e-3 * abs(tau_y)
    assert not d.degenerate


def test_midpoint_sits_between_the_charges():
    u, v = charge_pair("x", separation=6.0)
    d = dipole(div_of(u, v))
    assert d.m_x == pytest.approx(0.0, abs=0.05)
    assert d.m_y == pytest.approx(0.0, abs=0.05)


def test_zero_field_is_degenerate_and_silent():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        d = dipole(np.zeros(GRID_X.shape))
    assert d.degenerate and (d.p_x, d.p_y) == (0.0, 0.0)


def test_one_signed_divergence_is_the_moment_about_the_gel_centre():
    div = np.abs(div_of(*source(1.0, 0.0, 0.05))) + 1e-3
    d = dipole(div)
    assert not d.degenerate and d.midpoint_weight == 0.0 and (d.m_x, d.m_y) == (0.0, 0.0)
    assert d.p_x == pytest.approx((GRID_X * div).mean(), rel=1e-12)
    assert d.p_x > 0  # the press sits at +x


def test_sensor_centre_origin_uses_fixed_lever():
    fixed = DipoleMomentCalculator(X_MM, Y_MM, origin="sensor_centre")
    div = div_of(*charge_pair("y", 5.0))
    d = fixed(div)
    assert d.p_y == pytest.approx((np.meshgrid(X_MM, Y_MM)[1] * div).mean())
    assert (d.m_x, d.m_y) == (0.0, 0.0)


def test_nan_divergence_raises():
    div = np.zeros(GRID_X.shape)
    div[0, 0] = np.inf
    with pytest.raises(ValueError, match="NaN or inf"):
        dipole(div)


def test_unknown_origin_raises():
    with pytest.raises(ValueError, match="origin"):
        DipoleMomentCalculator(X_MM, Y_MM, origin="somewhere")


pair_params = dict(
    sep=st.floats(3.0, 8.0),
    strength=st.floats(0.005, 0.5),
    angle=st.floats(0.0, 2 * np.pi),
)


def rotated_pair(sep, strength, angle, cx=0.0, cy=0.0):
    h = sep / 2
    ox, oy = h * np.cos(angle), h * np.sin(angle)
    pu, pv = source(cx + ox, cy + oy, strength)
    nu, nv = source(cx - ox, cy - oy, -strength)
    return pu + nu, pv + nv


@settings(max_examples=40, deadline=None)
@given(**pair_params, scale=st.floats(0.1, 10.0))
def test_moment_is_linear_in_field_scale(sep, strength, angle, scale):
    u, v = rotated_pair(sep, strength, angle)
    d1, d2 = dipole(div_of(u, v)), dipole(div_of(scale * u, scale * v))
    assert d2.p_x == pytest.approx(scale * d1.p_x, rel=1e-9, abs=1e-15)
    assert d2.p_y == pytest.approx(scale * d1.p_y, rel=1e-9, abs=1e-15)


@settings(max_examples=40, deadline=None)
@given(**pair_params)
def test_rotating_field_by_90_degrees_rotates_torque(sep, strength, angle):
    # A square grid makes a 90-degree rotation map grid points onto grid points.
    from controller.tactile.field import grid_axes_mm

    xs, ys = grid_axes_mm(240, 240, 12, 12, 0.0634)
    gx, gy = np.meshgrid(xs, ys)
    calc = DipoleMomentCalculator(xs, ys)

    h = sep / 2
    ox, oy = h * np.cos(angle), h * np.sin(angle)
    pu, pv = charge_on(gx, gy, ox, oy, strength)
    nu, nv = charge_on(gx, gy, -ox, -oy, -strength)
    u, v = pu + nu, pv + nv
    # Rotate the field by +90 deg about z: new(x) = R old(R^T x), R = [[0,-1],[1,0]].
    # On the grid, R^T maps (x, y) to (y, -x): new[r, c] samples old at the rotated cell.
    u_rot = -np.rot90(v, k=1)
    v_rot = np.rot90(u, k=1)
    div = VectorField(xs, ys, u, v).divergence()
    div_rot = VectorField(xs, ys, u_rot, v_rot).divergence()
    d, d_rot = calc(div), calc(div_rot)
    # p rotates with the field: p' = R p = (-p_y, p_x); so tau' = (p'_y, -p'_x) = (p_x, p_y)
    assert d_rot.p_x == pytest.approx(-d.p_y, rel=1e-9, abs=1e-12)
    assert d_rot.p_y == pytest.approx(d.p_x, rel=1e-9, abs=1e-12)


@settings(max_examples=40, deadline=None)
@given(
    sep=st.floats(3.0, 5.0),
    strength=pair_params["strength"],
    angle=pair_params["angle"],
    shift_x=st.integers(-2, 2),
    shift_y=st.integers(-1, 1),
)
def test_translating_the_pattern_leaves_torque_unchanged(sep, strength, angle, shift_x, shift_y):
    spacing = X_MM[1] - X_MM[0]
    d0 = dipole(div_of(*rotated_pair(sep, strength, angle)))
    moved = rotated_pair(sep, strength, angle, cx=shift_x * spacing, cy=shift_y * spacing)
    d1 = dipole(div_of(*moved))
    scale = max(abs(d0.p_x), abs(d0.p_y))
    # Exact up to the charges' tails that cross the grid border (the grid is 15 x 20 mm).
    assert d1.p_x == pytest.approx(d0.p_x, abs=0.02 * scale)
    assert d1.p_y == pytest.approx(d0.p_y, abs=0.02 * scale)


def test_an_origin_rule_takes_the_moment_about_the_point_it_gives():
    x, y = np.linspace(-3.0, 3.0, 7), np.linspace(-2.0, 2.0, 5)
    div = np.random.default_rng(4).normal(size=(5, 7))
    centre = DipoleMomentCalculator(x, y, "sensor_centre")(div)
    about_zero = DipoleMomentCalculator(x, y, lambda d, gx, gy: (0.0, 0.0))(div)
    assert (about_zero.p_x, about_zero.p_y) == (centre.p_x, centre.p_y)
    moved = DipoleMomentCalculator(x, y, lambda d, gx, gy: (1.0, -0.5))(div)
    assert (moved.m_x, moved.m_y) == (1.0, -0.5)
    assert moved.p_x == pytest.approx(centre.p_x - 1.0 * div.sum() / div.size)
    assert moved.p_y == pytest.approx(centre.p_y + 0.5 * div.sum() / div.size)
