"""The dipole under a net press: the paper's rule where both signs of divergence are comparable,
continuous (Lipschitz) everywhere, meaningful when one sign is absent."""

import warnings

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from controller.tactile.dipole import (
    FULL_MIDPOINT_RATIO,
    DipoleMomentCalculator,
    midpoint_weight,
)
from controller.tactile.field import VectorField, block_mean, divergence
from controller.tactile.nhhd import CurlFreePart
from tests.controller.tactile.fields import GRID_X, GRID_Y, X_MM, Y_MM, charge_on, charge_pair

# The default's dipole grid: the 16 x 12 field block-averaged onto 4 x 4 blocks of 4 x 3 cells,
# then the divergence of its NHHD curl-free part there (as TactileEstimator does).
BLOCK = (3, 4)
X_BLOCKS = X_MM.reshape(4, -1).mean(axis=1)
Y_BLOCKS = Y_MM.reshape(4, -1).mean(axis=1)
_curl_free = CurlFreePart(X_BLOCKS, Y_BLOCKS)


def divergence_full(u, v):
    return VectorField(X_MM, Y_MM, u, v).divergence()


def divergence_blocks(u, v):
    coarse = (4, 4)
    d_u, d_v = _curl_free(
        block_mean(u, BLOCK, np.empty(coarse)), block_mean(v, BLOCK, np.empty(coarse))
    )
    dx, dy = X_BLOCKS[1] - X_BLOCKS[0], Y_BLOCKS[1] - Y_BLOCKS[0]
    return divergence(d_u, d_v, dx, dy, np.empty(coarse), np.empty(coarse)).copy()


GRIDS = {
    "full 16x12": (divergence_full, X_MM, Y_MM),
    "blocks 4x4": (divergence_blocks, X_BLOCKS, Y_BLOCKS),
}
# A uniform expansion u = x, v = y (a net press centred on the gel): divergence 2 everywhere.
EXPANSION = (GRID_X, GRID_Y)


def lipschitz_constant(x_mm, y_mm, full_ratio=FULL_MIDPOINT_RATIO):
    """Per axis, the bound L of |delta p| <= L sum |delta div| (controller/tactile/dipole.py):
    (2 + 2.625 / full_ratio) R / N, R the grid's largest |coordinate| on that axis."""
    n = x_mm.size * y_mm.size
    reach = np.array([np.abs(x_mm).max(), np.abs(y_mm).max()])
    return (2.0 + 2.625 / full_ratio) * reach / n


def papers_rule(x_mm, y_mm, div):
    """Slow reference: the paper's p = (1/N) sum (x_i - m) div_i, m the midpoint of the
    div-weighted centroids of the positive and of the negative points."""
    points = [(x, y, div[r, c]) for r, y in enumerate(y_mm) for c, x in enumerate(x_mm)]
    pos = [(x, y, d) for x, y, d in points if d > 0]
    neg = [(x, y, -d) for x, y, d in points if d < 0]

    def centroid(region):
        mass = sum(d for _, _, d in region)
        return sum(x * d for x, _, d in region) / mass, sum(y * d for _, y, d in region) / mass

    (px, py), (nx, ny) = centroid(pos), centroid(neg)
    mx, my = (px + nx) / 2, (py + ny) / 2
    return (
        sum((x - mx) * d for x, _, d in points) / len(points),
        sum((y - my) * d for _, y, d in points) / len(points),
    )


def masses(div):
    return float(div[div > 0].sum()), float(-div[div < 0].sum())


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), offset=st.floats(-0.4, 0.4))
def test_comparable_signs_give_the_papers_rule_exactly(seed, offset):
    div = np.random.default_rng(seed).normal(size=GRID_X.shape) + offset
    positive, negative = masses(div)
    assume(min(positive, negative) >= FULL_MIDPOINT_RATIO * max(positive, negative))
    d = DipoleMomentCalculator(X_MM, Y_MM)(div)
    p_x, p_y = papers_rule(X_MM, Y_MM, div)
    assert d.midpoint_weight == 1.0 and not d.degenerate
    assert d.p_x == pytest.approx(p_x, rel=1e-9, abs=1e-12)
    assert d.p_y == pytest.approx(p_y, rel=1e-9, abs=1e-12)


def test_weight_is_a_smooth_step():
    full = 0.25
    rho = np.linspace(0.0, 2 * full, 2001)
    w = np.array([midpoint_weight(r, full) for r in rho])
    assert w[0] == 0.0 and np.all(w[rho >= full] == 1.0)
    assert np.all(np.diff(w) >= 0)
    slope = np.diff(w) / np.diff(rho)
    assert slope.max() <= 1.5 / full + 1e-9
    assert slope[0] < 0.02 and slope[rho[1:] <= full][-1] < 0.02  # flat at both ends (max 6)


@pytest.mark.parametrize("full_ratio", [0.1, FULL_MIDPOINT_RATIO, 1.0])
@settings(max_examples=80, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    offset=st.floats(-3.0, 3.0),
    step=st.sampled_from([1e-6, 1e-3, 0.1, 1.0, 5.0]),
)
def test_moment_is_lipschitz_in_the_divergence(full_ratio, seed, offset, step):
    """Offsets up to 3 standard deviations make one sign rare or absent, where the paper's
    centroid of the weaker region is ill-defined; the bound holds there too."""
    rng = np.random.default_rng(seed)
    div = rng.normal(size=GRID_X.shape) + offset
    change = step * rng.normal(size=GRID_X.shape)
    calc = DipoleMomentCalculator(X_MM, Y_MM, full_midpoint_ratio=full_ratio)
    a, b = calc(div), calc(div + change)
    bound = lipschitz_constant(X_MM, Y_MM, full_ratio) * np.abs(change).sum()
    assert abs(b.p_x - a.p_x) <= bound[0] * (1 + 1e-9)
    assert abs(b.p_y - a.p_y) <= bound[1] * (1 + 1e-9)


@pytest.mark.parametrize("axis", ["x", "y"])
@pytest.mark.parametrize("grid", GRIDS)
def test_tilt_under_a_growing_press_changes_smoothly(grid, axis):
    """A tilt (a charge pair) plus a uniform expansion b * (x, y), b swept finely from 0 to
    1.5 times the press at which the negative divergence vanishes."""
    div_of, x_mm, y_mm = GRIDS[grid]
    calc = DipoleMomentCalculator(x_mm, y_mm)
    tilt = div_of(*charge_pair(axis, separation=5.0, q=0.05))
    press = div_of(*EXPANSION)
    vanishes = float(-tilt.min() / press.min())
    amplitudes = np.linspace(0.0, 1.5 * vanishes, 20001)
    k = 0 if axis == "x" else 1
    moments = np.array(
        [
            (d.p_x, d.p_y, d.midpoint_weight)
            for d in map(calc, (tilt + b * press for b in amplitudes))
        ]
    )
    p, across, weight = moments[:, k], moments[:, 1 - k], moments[:, 2]
    assert np.all(np.isfinite(moments))
    # The sweep runs from the paper's rule (balanced) to no negative divergence at all.
    assert weight[0] == 1.0 and weight[-1] == 0.0 and masses(tilt + amplitudes[-1] * press)[1] == 0
    # Bounded derivative: |dp/db| <= L sum |press| (the Lipschitz bound along this path) ...
    slope_bound = lipschitz_constant(x_mm, y_mm)[k] * np.abs(press).sum()
    slopes = np.abs(np.diff(p)) / np.diff(amplitudes)
    assert slopes.max() <= slope_bound
    # ... on a sweep fine enough that a jump of a fifth of the tilt would break it.
    assert slope_bound * (amplitudes[1] - amplitudes[0]) < 0.2 * abs(p[0])
    # Meaningful: the tilt keeps its sign and stays within the paper's own press bias of the
    # unpressed reading; once one sign is gone it is the moment about the gel centre, which
    # a centred press does not change; nothing leaks across.
    assert np.all(p / p[0] >= 1.0 - 1e-9) and np.all(p / p[0] <= 1.5)
    assert p[-1] == pytest.approx(p[0], rel=1e-9)
    assert np.abs(across).max() <= 1e-9 * abs(p[0])


@pytest.mark.parametrize("grid", GRIDS)
def test_tilt_is_linear_at_a_fixed_press(grid):
    """Under a press that leaves only positive divergence, the estimate is linear in the tilt
    (it is the moment about a fixed point), and has the tilt's sign."""
    div_of, x_mm, y_mm = GRIDS[grid]
    calc = DipoleMomentCalculator(x_mm, y_mm)
    tilt = div_of(*charge_pair("y", separation=5.0, q=0.05))
    press = div_of(*EXPANSION)
    b = 2.0 * float(-tilt.min() / press.min())
    unit = calc(tilt + b * press).p_y - calc(b * press).p_y
    for scale in (-1.0, -0.5, -0.1, 0.1, 0.5, 1.0):
        d = calc(scale * tilt + b * press)
        assert masses(scale * tilt + b * press)[1] == 0.0
        assert d.p_y - calc(b * press).p_y == pytest.approx(scale * unit, rel=1e-9, abs=1e-15)
        assert np.sign(d.tilt_torque_raw[0]) == np.sign(scale)


@settings(max_examples=60, deadline=None)
@given(
    grid=st.sampled_from(sorted(GRIDS)),
    angle=st.floats(0.0, 2 * np.pi),
    strength=st.floats(0.005, 0.5),
    press=st.floats(-3.0, 3.0),
)
def test_tilt_keeps_its_sign_under_press_and_release(grid, angle, strength, press):
    """A tilt along ``angle`` plus a centred press or release of up to three times the
    press that removes one sign: the moment points along the tilt."""
    div_of, x_mm, y_mm = GRIDS[grid]
    h = 2.5
    ox, oy = h * np.cos(angle), h * np.sin(angle)
    pu, pv = charge_on(GRID_X, GRID_Y, ox, oy, strength)
    nu, nv = charge_on(GRID_X, GRID_Y, -ox, -oy, -strength)
    tilt = div_of(pu + nu, pv + nv)
    expansion = div_of(*EXPANSION)
    d = DipoleMomentCalculator(x_mm, y_mm)(tilt + press * float(np.abs(tilt).max()) * expansion)
    assert d.p_x * np.cos(angle) + d.p_y * np.sin(angle) > 0


@pytest.mark.parametrize(
    "make",
    [
        lambda: np.zeros(GRID_X.shape),
        lambda: np.full(GRID_X.shape, 5e-324),
        lambda: np.full(GRID_X.shape, -1e-300),
        lambda: np.where(GRID_X > 0, 1e300, -1e300),
        lambda: np.eye(*GRID_X.shape),
        lambda: -np.eye(*GRID_X.shape)[::-1],
        lambda: np.abs(np.random.default_rng(1).normal(size=GRID_X.shape)),
    ],
    ids=["zero", "denormal", "tiny one-signed", "huge", "a line", "a negative line", "one-signed"],
)
@pytest.mark.parametrize("origin", ["centroid_midpoint", "sensor_centre"])
def test_degenerate_input_gives_finite_output_silently(make, origin):
    div = make()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        d = DipoleMomentCalculator(X_MM, Y_MM, origin)(div)
    values = (d.p_x, d.p_y, d.m_x, d.m_y, d.midpoint_weight)
    assert all(np.isfinite(values))
    assert d.degenerate == (not div.any())


@pytest.mark.parametrize("ratio", [0.0, -0.1, 1.5, float("nan")])
def test_bad_full_midpoint_ratio_raises(ratio):
    with pytest.raises(ValueError, match="full_midpoint_ratio"):
        DipoleMomentCalculator(X_MM, Y_MM, full_midpoint_ratio=ratio)


@pytest.mark.parametrize("grid", sorted(GRIDS))
def test_the_grasp_centroid_rule_is_lipschitz_under_a_growing_press(grid):
    """With the grasp's support set (an off-centre press), a tilt plus a uniform expansion
    swept from balanced to one-signed moves p by at most (2 R / N) sum |delta div| per step
    (p is linear in div, its lever |w (x - c)| at most 2 R), and linearly in the press."""
    from controller.tactile.dipole import grasp_support

    div_of, x_mm, y_mm = GRIDS[grid]
    gx, gy = np.meshgrid(x_mm, y_mm)
    press = np.exp(-((gx - 2.0) ** 2 + (gy + 1.0) ** 2) / 18.0)
    calculator = DipoleMomentCalculator(x_mm, y_mm, "grasp_centroid")
    calculator.set_grasp_support(grasp_support(press, x_mm, y_mm))
    tilt = div_of(*charge_pair("x", 6.0))
    expansion = div_of(*EXPANSION)
    n = x_mm.size * y_mm.size
    bound = 2.0 * np.array([np.abs(x_mm).max(), np.abs(y_mm).max()]) / n
    scales = np.linspace(0.0, 3.0 * np.abs(tilt).max() / np.abs(expansion).max(), 20001)
    readings = np.array([[(m := calculator(tilt + s * expansion)).p_x, m.p_y] for s in scales])
    step = np.abs(scales[1] - scales[0]) * np.abs(expansion).sum()
    assert (np.abs(np.diff(readings, axis=0)) <= bound * step * (1 + 1e-9) + 1e-15).all()
    second = np.diff(readings, 2, axis=0)  # linear in the press: no curvature
    assert np.abs(second).max() < 1e-9 * np.abs(readings).max()
