"""The ``grasp_centroid`` dipole: the contact's support and centre from the closing press, the
tilt weighted by it and taken about it, invariant to the grip pressure; and the estimator's
open-gel API (capture_open, set_open_reference) with its fallback."""

from dataclasses import replace

import numpy as np
import pytest

from controller.tactile import TactileEstimator, estimator_config
from controller.tactile.dipole import DipoleMomentCalculator, GraspSupport, grasp_support
from controller.tactile.field import VectorField
from core.sensor_profile import sensor_profile
from tests.controller.tactile.fields import GRID_X, GRID_Y, X_MM, Y_MM, charge_on

# An off-centre rectangular contact (mm, frame S) on the 16 x 12 grid, its pressure spread
# as many small Gaussian charges 0.25 mm apart (the gel smears its edges by ~0.6 mm).
CONTACT_CENTRE = (2.3, -1.4)
HALF = (4.0, 3.0)
SPACING = 0.25
_xs = np.arange(-HALF[0] + SPACING / 2, HALF[0], SPACING) + CONTACT_CENTRE[0]
_ys = np.arange(-HALF[1] + SPACING / 2, HALF[1], SPACING) + CONTACT_CENTRE[1]
POINTS = [(x, y) for y in _ys for x in _xs]


def pressure_field(weights):
    """The field of charges of size weights[k] * SPACING^2 at POINTS (divergence ~ the
    pressure change, smeared), on the 16 x 12 grid."""
    u, v = np.zeros_like(GRID_X), np.zeros_like(GRID_X)
    for (x, y), w in zip(POINTS, weights, strict=True):
        du, dv = charge_on(GRID_X, GRID_Y, x, y, w * SPACING**2, width=0.6)
        u += du
        v += dv
    return u, v


@pytest.fixture(scope="module")
def fields():
    """(press, tilt): divergence of a uniform press over the contact and of a tilt
    (x - c_x along x) across it; half the press changes the edges' pressure as much as the
    tilt does (at the extremes of a +-50% swing one edge just unloads)."""
    press = pressure_field(np.full(len(POINTS), 0.16))
    tilt = pressure_field(np.array([0.02 * (x - CONTACT_CENTRE[0]) for x, _ in POINTS]))
    div = [VectorField(X_MM, Y_MM, *f).divergence() for f in (press, tilt)]
    return div[0], div[1]


def test_the_support_of_the_closing_press_finds_the_contact(fields):
    press, _ = fields
    support = grasp_support(press, X_MM, Y_MM)
    assert np.hypot(*np.subtract(support.centre_mm, CONTACT_CENTRE)) < 0.15
    inside = (np.abs(GRID_X - CONTACT_CENTRE[0]) < HALF[0] - 1.5) & (
        np.abs(GRID_Y - CONTACT_CENTRE[1]) < HALF[1] - 1.5
    )
    outside = (np.abs(GRID_X - CONTACT_CENTRE[0]) > HALF[0] + 1.5) | (
        np.abs(GRID_Y - CONTACT_CENTRE[1]) > HALF[1] + 1.5
    )
    assert support.weights[inside].min() == 1.0 and support.weights[outside].max() == 0.0
    negated = grasp_support(-press, X_MM, Y_MM)  # a gel that contracts: the same contact
    np.testing.assert_allclose(negated.weights, support.weights)
    assert grasp_support(np.zeros_like(press), X_MM, Y_MM) is None


def test_the_tilt_about_the_grasp_is_invariant_to_the_grip_pressure(fields):
    press, tilt = fields
    grasp = DipoleMomentCalculator(X_MM, Y_MM, "grasp_centroid")
    grasp.set_grasp_support(grasp_support(press, X_MM, Y_MM))
    midpoint = DipoleMomentCalculator(X_MM, Y_MM, "centroid_midpoint")
    base_grasp, base_midpoint = grasp(tilt).p_x, midpoint(tilt).p_x
    assert base_grasp > 0 and base_midpoint > 0
    leak_grasp = leak_midpoint = 0.0
    for change in np.linspace(-0.5, 0.5, 11):  # the grip swings by +-50%
        div = tilt + change * press
        leak_grasp = max(leak_grasp, abs(grasp(div).p_x - base_grasp) / base_grasp)
        leak_midpoint = max(leak_midpoint, abs(midpoint(div).p_x - base_midpoint) / base_midpoint)
        assert abs(grasp(div).p_y) < 0.05 * base_grasp
    assert leak_grasp < 0.05  # the press drops out
    assert leak_midpoint > 0.5  # ... which it does not about the centroid midpoint


def test_without_a_support_the_rule_is_the_centroid_midpoints(fields):
    press, tilt = fields
    grasp = DipoleMomentCalculator(X_MM, Y_MM, "grasp_centroid")
    midpoint = DipoleMomentCalculator(X_MM, Y_MM, "centroid_midpoint")
    for div in (tilt, tilt + 0.3 * press, press):
        assert grasp(div) == midpoint(div)
    grasp.set_grasp_support(grasp_support(press, X_MM, Y_MM))
    grasp.set_grasp_support(None)
    assert grasp(tilt + 0.3 * press) == midpoint(tilt + 0.3 * press)


def test_a_support_must_fit_the_grid():
    grasp = DipoleMomentCalculator(X_MM, Y_MM, "grasp_centroid")
    with pytest.raises(ValueError, match="192 grid values"):
        grasp.set_grasp_support(GraspSupport(np.ones((4, 4)), (0.0, 0.0)))
    with pytest.raises(ValueError, match="finite"):
        grasp.set_grasp_support(GraspSupport(np.full((12, 16), np.nan), (0.0, 0.0)))


# -- the estimator's open gel -------------------------------------------------------------------

PROFILE = sensor_profile("gelsight_mini")
GRID_LK = estimator_config("default")
PRESS_CENTRE_PX = (200.0, 100.0)  # right of and above the image centre (160, 120)


def press_px(amplitude=2.0):
    """A compact bulge centred at PRESS_CENTRE_PX: the grasp's field, px."""
    ys, xs = np.mgrid[0:240, 0:320].astype(float)
    dx, dy = xs - PRESS_CENTRE_PX[0], ys - PRESS_CENTRE_PX[1]
    k = amplitude / 30.0 * np.exp(-(dx**2 + dy**2) / (2 * 30.0**2))
    return np.stack([k * dx, k * dy], axis=-1)


def test_capture_open_then_rezero_locates_the_contact(renderer):
    est = TactileEstimator(GRID_LK, PROFILE)
    est.capture_open(2)
    for i in range(2):
        assert est.push(renderer.render(), 0.1 * i).zeroing
    grasped = renderer.render(press_px())
    waiting = est.push(grasped, 0.3)  # closed, settling: no reference until rezero
    assert waiting.zeroing and not est.is_zeroed and est.contact_centre_mm is None
    est.rezero(2)
    for i in range(2):
        assert est.push(grasped, 0.4 + 0.1 * i).zeroing
    assert est.is_zeroed
    x_mm, y_mm = est.contact_centre_mm
    mm = PROFILE.mm_per_px
    assert x_mm == pytest.approx((PRESS_CENTRE_PX[0] - 160) * mm, abs=0.5)
    assert y_mm == pytest.approx((PRESS_CENTRE_PX[1] - 120) * mm, abs=0.5)
    est.rezero(1)  # a later re-zero (after slip) measures again against the same open gel
    est.push(grasped, 1.0)
    assert est.contact_centre_mm == pytest.approx((x_mm, y_mm), abs=0.05)


def test_without_the_open_gel_grid_lk_is_the_centroid_midpoint_rule(renderer):
    midpoint = TactileEstimator(replace(GRID_LK, dipole_origin="centroid_midpoint"), PROFILE)
    est = TactileEstimator(GRID_LK, PROFILE)
    reference = renderer.render(press_px())
    for e in (est, midpoint):
        e.set_reference(reference)
    assert est.contact_centre_mm is None
    frame = renderer.render(press_px(2.4))
    a, b = est.push(frame, 0.0), midpoint.push(frame, 0.0)
    assert (a.tau_x, a.tau_y) == (b.tau_x, b.tau_y)


def test_no_contact_in_the_grasp_falls_back(renderer):
    est = TactileEstimator(GRID_LK, PROFILE)
    est.set_open_reference([renderer.render()])
    est.set_reference(renderer.render())
    assert est.contact_centre_mm is None and est.is_zeroed


def test_open_frames_of_another_size_are_refused_and_can_be_forgotten(renderer):
    est = TactileEstimator(GRID_LK, PROFILE)
    est.set_open_reference(renderer.render())
    est.set_reference(renderer.render(press_px()))
    centre = est.contact_centre_mm
    assert centre is not None
    est.set_open_reference(renderer.render()[::2, ::2].copy())
    with pytest.raises(ValueError, match="open gel"):
        est.set_reference(renderer.render(press_px()))
    assert est.is_zeroed and est.contact_centre_mm == centre  # left as it was
    est.set_open_reference(None)
    est.set_reference(renderer.render(press_px()))
    assert est.contact_centre_mm is None
    with pytest.raises(ValueError, match="capture_open needs a whole number"):
        est.capture_open(0)


def test_a_given_support_serves_where_the_open_gel_gives_none(renderer):
    """set_contact_support (the offline tool's support from a whole recording): used for the
    references the open gel does not locate, behind the no-contact gate; the open gel's own
    support comes first; one that does not fit the grid is refused, leaving the estimator as
    it was; None forgets it."""
    reference = renderer.render(press_px())
    weights = np.zeros((12, 16))
    weights[3:7, 9:13] = 1.0
    given = GraspSupport(weights, (2.5, -1.5))
    est = TactileEstimator(GRID_LK, PROFILE)
    est.set_contact_support(given)
    est.set_reference(reference)
    assert est.contact_centre_mm == (2.5, -1.5) and est.noise_gated
    about = DipoleMomentCalculator(X_MM, Y_MM, "grasp_centroid")
    about.set_grasp_support(given)
    frame = renderer.render(press_px(2.4))
    estimate = est.push(frame, 0.0)
    dipole = about(est.field_divergence())
    assert estimate.tau_x == pytest.approx(dipole.tilt_torque_raw[0], rel=1e-12, abs=1e-15)
    est.set_open_reference([renderer.render()])
    est.set_reference(reference)  # the open gel locates the press: its support, no gate
    assert est.contact_centre_mm != (2.5, -1.5) and not est.noise_gated
    est.set_open_reference(None)
    est.set_contact_support(GraspSupport(np.ones((4, 4)), (0.0, 0.0)))
    with pytest.raises(ValueError, match="grasp support must have 192 grid values"):
        est.set_reference(reference)
    assert not est.noise_gated  # left as it was
    est.set_contact_support(None)
    est.set_reference(reference)
    assert est.contact_centre_mm is None and est.noise_gated
