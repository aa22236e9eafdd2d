"""Slip detector, re-zero policy and their wiring into the estimator.

Analytic fields on the default 16 x 12 grid (frame S, mm): a contact that moves rigidly with
the object (stick), and one whose periphery has stopped while its core keeps moving (partial
slip: the stuck core carries every further load increment).
"""

from dataclasses import replace

import numpy as np
import pytest

from controller.tactile import TactileEstimator, VectorField, estimator_for_sensor
from controller.tactile.nhhd import NHHD
from controller.tactile.settings import estimator_config
from controller.tactile.slip import (
    CoreFit,
    RezeroPolicy,
    RezeroState,
    SlipDetector,
    SlipStatus,
    next_rezero_state,
)
from core.sensor_profile import sensor_profile
from tests.controller.tactile.fields import GRID_X, GRID_Y, X_MM, Y_MM, charge_pair

CONFIG = estimator_config("default")
SLIP = CONFIG.slip
REZERO = SLIP.rezero
NHHD_GRID = NHHD(X_MM, Y_MM)
CORE = np.exp(-(GRID_X**2 + GRID_Y**2) / (2 * 3.0**2))  # Gaussian core, 3 mm wide
FRAME_S = 0.04


def rigid(a: float) -> tuple[np.ndarray, np.ndarray]:
    """Translation (a, a/2) mm plus a rotation of a/20 rad about (1, -1) mm."""
    omega = a / 20
    return a - omega * (GRID_Y + 1), a / 2 + omega * (GRID_X - 1)


def lagging(stuck: float, extra: float) -> tuple[np.ndarray, np.ndarray]:
    """Everything stuck moved ``stuck`` mm along x; then only the core moved on, by up to
    ``extra`` mm: the periphery lags."""
    u = stuck + extra * CORE
    return u, np.zeros_like(u)


def stick_then_slip(steps: int = 5) -> list[tuple[np.ndarray, np.ndarray]]:
    stick = [lagging(0.06 * k, 0.0) for k in range(1, steps + 1)]
    slip = [lagging(0.06 * steps, 0.08 * k) for k in range(1, steps + 1)]
    return stick + slip


def feed(detector: SlipDetector, fields, t0: float = 0.0) -> list[SlipStatus]:
    statuses = []
    for i, (u, v) in enumerate(fields):
        decomposition = NHHD_GRID.decompose(u, v)
        field = VectorField(X_MM, Y_MM, u, v)
        statuses.append(detector.update(field, decomposition, t0 + i * FRAME_S))
    return statuses


# -- the fit -------------------------------------------------------------------------------


def test_core_fit_explains_affine_motion_and_measures_the_rest():
    fit = CoreFit(GRID_X, GRID_Y)
    fit.set_weights(CORE > 0.3)
    u, v = rigid(0.2)
    (tx, ty, rotation), residual = fit.motion(u, v)
    assert residual < 1e-7
    assert rotation > 0  # positive rotation: from +x toward +y
    stretch_u, stretch_v = 0.01 * GRID_X + 0.1, 0.02 * GRID_Y
    assert fit.motion(stretch_u, stretch_v)[1] < 1e-7
    assert fit.motion(*lagging(0.0, 0.3))[1] > 0.1
    assert fit.motion(np.zeros_like(u), np.zeros_like(u)) == ((0.0, 0.0, 0.0), 0.0)


def test_core_fit_handles_a_single_row_and_a_single_cell():
    fit = CoreFit(GRID_X, GRID_Y)
    row = np.zeros(GRID_X.shape)
    row[5] = 1.0
    fit.set_weights(row)
    u = 0.1 + 0.01 * GRID_X  # affine along the row: explained
    assert fit.motion(u, np.zeros_like(u))[1] < 1e-7
    cell = np.zeros(GRID_X.shape)
    cell[5, 5] = 1.0
    fit.set_weights(cell)
    assert fit.motion(u, u)[1] == pytest.approx(0.0, abs=1e-7)
    with pytest.raises(ValueError, match="weights"):
        fit.set_weights(np.zeros(GRID_X.shape))


# -- the detector --------------------------------------------------------------------------


def test_a_rigidly_moving_contact_never_slips():
    statuses = feed(SlipDetector(SLIP, X_MM, Y_MM), [rigid(0.05 * k) for k in range(1, 15)])
    assert not any(s.incipient or s.gross for s in statuses)
    assert max(abs(s.score) for s in statuses) < 0.01
    assert statuses[-1].load_mm > 0.5


def test_a_lagging_periphery_is_incipient_slip_and_only_after_the_lag_starts():
    statuses = feed(SlipDetector(SLIP, X_MM, Y_MM), stick_then_slip())
    assert not any(s.incipient for s in statuses[:5])
    assert all(s.incipient for s in statuses[6:])
    assert min(s.score for s in statuses[6:]) > SLIP.incipient_score


def test_the_incipient_threshold_is_respected():
    score = feed(SlipDetector(SLIP, X_MM, Y_MM), stick_then_slip())[-1].score
    above = replace(SLIP, incipient_score=score + 1e-3, gross_score=1.0)
    below = replace(SLIP, incipient_score=score - 1e-3, gross_score=1.0)
    assert not feed(SlipDetector(above, X_MM, Y_MM), stick_then_slip())[-1].incipient
    assert feed(SlipDetector(below, X_MM, Y_MM), stick_then_slip())[-1].incipient


def test_below_the_minimum_field_nothing_slips():
    small = [(0.01 * u, 0.01 * v) for u, v in stick_then_slip()]  # largest cell < 0.05 mm
    statuses = feed(SlipDetector(SLIP, X_MM, Y_MM), small)
    assert not any(s.incipient for s in statuses)
    assert all(s.score == 0.0 for s in statuses)


def test_tilts_and_sideways_increments_are_not_judged():
    """A growing divergence dipole (a tilt) and a sideways load on a stuck shear are not
    loading increments of the tangential load: no slip."""
    tilt = [tuple(k * c for c in charge_pair("y", 4.0, 0.3)) for k in range(1, 10)]
    assert not any(s.incipient for s in feed(SlipDetector(SLIP, X_MM, Y_MM), tilt))
    shear = [lagging(0.06 * k, 0.0) for k in range(1, 6)]
    # A non-rigid increment along y, while the load stays mostly along x (< 60 degrees off).
    sideways = [(shear[-1][0], 0.03 * k * CORE) for k in range(1, 6)]
    statuses = feed(SlipDetector(SLIP, X_MM, Y_MM), shear + sideways)
    assert not any(s.incipient for s in statuses)


def _vortex_quadrupole(cx: float, cy: float, spacing: float) -> tuple[np.ndarray, np.ndarray]:
    """Four alternately turning Gaussian vortices around (cx, cy), mm: divergence-free, with no
    net translation or rotation, and not affine."""
    u, v = np.zeros_like(GRID_X), np.zeros_like(GRID_X)
    for sx, sy, sign in ((1, 1, 1), (-1, 1, -1), (-1, -1, 1), (1, -1, -1)):
        dx, dy = GRID_X - cx - sx * spacing, GRID_Y - cy - sy * spacing
        g = sign * np.exp(-(dx**2 + dy**2) / (2 * 2.0**2))
        u, v = u - dy * g, v + dx * g
    return u, v


def test_pushing_and_tilting_without_slip_raises_no_flag():
    """The normal load swings by +-50% (twice) during a tilt there and back. Its radial field
    goes to the diverging part; what flow and decomposition leak into the divergence-free
    part grows with the load, nearly along itself (a small translation on a non-affine
    pattern), so each push passes the loading test with a large residual. It moves no
    stuck core rigidly, so it is not judged (the detector before this gate flagged every
    frame of this sequence)."""
    k = np.arange(60)
    load = 1.0 + 0.5 * np.sin(2 * np.pi * 2 * k / 60)
    tilt = np.sin(2 * np.pi * k / 60)
    press, lean = _vortex_quadrupole(0.0, 0.0, 3.0), _vortex_quadrupole(1.5, -1.0, 2.0)
    scale = 0.1 / float(np.hypot(*press).max())
    fields = []
    for a, b in zip(load, tilt, strict=True):
        radial = 0.1 * a * np.exp(-(GRID_X**2 + GRID_Y**2) / 50)
        u = radial * GRID_X + scale * (a * (press[0] + 0.1) + 0.5 * b * lean[0])
        v = radial * GRID_Y + scale * (a * press[1] + 0.5 * b * lean[1])
        fields.append((u, v))
    statuses = feed(SlipDetector(SLIP, X_MM, Y_MM), fields)
    assert max(s.load_mm for s in statuses) > SLIP.min_field_mm  # loaded: it was judged
    assert not any(s.incipient or s.gross for s in statuses)


def test_gross_slip_needs_a_plateau_and_ends_when_the_load_falls():
    detector = SlipDetector(SLIP, X_MM, Y_MM)
    fields = stick_then_slip()
    statuses = feed(detector, fields)
    assert statuses[-1].score >= SLIP.gross_score and not statuses[-1].gross  # still growing
    held = feed(detector, [fields[-1]] * 3, t0=len(fields) * FRAME_S)
    assert [s.gross for s in held] == [False, True, True]  # confirmed after 0.06 s
    assert all(s.incipient for s in held)
    u, v = fields[-1]
    released = feed(detector, [(0.85 * u, 0.85 * v)], t0=(len(fields) + 3) * FRAME_S)
    assert not released[0].gross


def test_reset_forgets_the_grasp():
    detector = SlipDetector(SLIP, X_MM, Y_MM)
    feed(detector, stick_then_slip())
    assert detector.baseline < SLIP.baseline_max
    detector.reset()
    assert detector.baseline == SLIP.baseline_max
    first = feed(detector, [rigid(0.1)])[0]
    assert not first.incipient and first.change_mm == 0.0


def test_bad_inputs_are_named():
    detector = SlipDetector(SLIP, X_MM, Y_MM)
    u, v = rigid(0.1)
    decomposition = NHHD_GRID.decompose(u, v)
    with pytest.raises(ValueError, match="NaN"):
        detector.update(VectorField(X_MM, Y_MM, u * np.nan, v), decomposition, 0.0)
    small = VectorField(X_MM[:4], Y_MM[:4], u[:4, :4], v[:4, :4])
    with pytest.raises(ValueError, match="shape"):
        detector.update(small, decomposition, 0.0)


# -- the re-zero policy --------------------------------------------------------------------


def status(gross=False, load=0.0, change=0.0) -> SlipStatus:
    return SlipStatus(incipient=gross, gross=gross, score=0.0, load_mm=load, change_mm=change)


def run_policy(policy: RezeroPolicy, statuses, t0: float = 0.0) -> list[bool]:
    return [policy.update(s, t0 + i * FRAME_S) for i, s in enumerate(statuses)]


def test_no_recommendation_without_gross_slip():
    policy = RezeroPolicy(REZERO)
    assert not any(run_policy(policy, [status()] * 50))
    assert policy.state == RezeroState()


def test_no_recommendation_while_loaded_one_after_release_and_quiet():
    policy = RezeroPolicy(REZERO)
    run_policy(policy, [status(gross=True, load=0.5)] * 3)
    assert policy.state.phase == "slipped" and policy.state.peak_load_mm == 0.5
    # Still loaded (more than 20% of the slip's peak) and perfectly quiet: never.
    assert not any(run_policy(policy, [status(load=0.3)] * 40, t0=1.0))
    # Released but the field still moves: not yet.
    assert not any(run_policy(policy, [status(load=0.05, change=0.05)] * 20, t0=3.0))
    # Released and quiet: after quiet_s (0.4 s = 10 frames at 25 Hz).
    quiet = run_policy(policy, [status(load=0.05)] * 15, t0=4.0)
    assert quiet.index(True) == round(REZERO.quiet_s / FRAME_S)
    assert all(quiet[quiet.index(True) :]) and policy.state.recommended
    # A load or motion withdraws it; gross slip again restarts the wait; reset re-arms.
    assert not policy.update(status(load=0.2), 5.0)
    policy.update(status(gross=True, load=0.7), 5.1)
    assert policy.state == RezeroState("slipped", 0.7, None)
    policy.reset()
    assert policy.state == RezeroState()


def test_the_transition_is_a_pure_function():
    state = RezeroState("slipped", 0.5, None)
    first = next_rezero_state(REZERO, state, status(load=0.01), 1.0)
    again = next_rezero_state(REZERO, state, status(load=0.01), 1.0)
    assert first == again == RezeroState("slipped", 0.5, 1.0)
    assert state == RezeroState("slipped", 0.5, None)
    settled = next_rezero_state(REZERO, first, status(load=0.01), 1.0 + REZERO.quiet_s)
    assert settled.recommended


# -- the estimator -------------------------------------------------------------------------


def frames(renderer):
    """Rendered frames: a stuck contact translated along x, then a core moving on while the
    periphery stays (0.8 px steps, above the 0.04 mm evaluation step), then held."""
    ys, xs = np.mgrid[0:240, 0:320].astype(np.float64)
    core = np.exp(-((xs - 160) ** 2 + (ys - 120) ** 2) / (2 * 60.0**2))

    def image(stuck: float, extra: float) -> np.ndarray:
        field = np.zeros((240, 320, 2), np.float32)
        field[..., 0] = stuck + extra * core
        return renderer.render(field)

    stick = [image(0.8 * k, 0.0) for k in range(1, 5)]
    slip = [image(3.2, 0.8 * k) for k in range(1, 6)]
    return stick, slip


@pytest.fixture(scope="module")
def slipping(renderer):
    return frames(renderer)


def push_all(est, images, t0):
    return [est.push(image, t0 + i * FRAME_S) for i, image in enumerate(images)]


def test_estimator_flags_slip_gross_slip_and_recommends_a_rezero(renderer, slipping):
    stick, slip = slipping
    est = estimator_for_sensor("gelsight_mini", "default")
    est.set_reference(renderer.render())
    estimates = push_all(est, stick + slip + [slip[-1]] * 3, 0.0)
    assert not any(e.slip_suspected for e in estimates[:4])
    assert all(e.slip_suspected for e in estimates[6:])
    assert not any(e.slip_gross for e in estimates[:9]) and estimates[-1].slip_gross
    assert est.last_slip_status.gross
    rest = push_all(est, [renderer.render()] * 14, 1.0)
    # The load vanishes at once in this test: the default's warm-started flow needs the first
    # unloaded frame to catch up, so the detector may still see motion there, never later.
    assert not any(e.slip_suspected or e.slip_gross for e in rest[1:])
    assert not rest[0].rezero_recommended and rest[-1].rezero_recommended
    assert est.rezero_state.phase == "settled"
    est.rezero()
    assert est.rezero_state.phase == "armed"


def test_auto_rezero_captures_a_new_reference(renderer, slipping):
    stick, slip = slipping
    auto = replace(CONFIG, slip=replace(SLIP, rezero=replace(REZERO, auto=True)))
    est = TactileEstimator(auto, sensor_profile("gelsight_mini"))
    est.set_reference(renderer.render())
    push_all(est, stick + slip + [slip[-1]] * 3, 0.0)
    rest = push_all(est, [renderer.render()] * 20, 1.0)
    fired = next(i for i, e in enumerate(rest) if e.rezero_recommended)
    assert rest[fired + 1].zeroing and est.is_zeroed
    assert est.rezero_state.phase == "armed"


def test_disabled_detector_leaves_the_flags_off(renderer, slipping):
    stick, slip = slipping
    off = replace(CONFIG, slip=replace(SLIP, enabled=False))
    est = TactileEstimator(off, sensor_profile("gelsight_mini"))
    est.set_reference(renderer.render())
    estimates = push_all(est, stick + slip, 0.0)
    assert not any(e.slip_suspected or e.slip_gross or e.rezero_recommended for e in estimates)
    assert est.last_slip_status is None
