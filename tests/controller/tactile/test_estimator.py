import tracemalloc
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from controller.tactile import Calibration, TactileEstimator, estimator_config, estimator_for_sensor
from controller.tactile.calibration import AxisFit
from controller.tactile.settings import DipoleGrid
from core.config import CONFIG_ROOT, ConfigError
from core.sensor_profile import sensor_profile
from drivers.sim.scenes.synthetic_sequence import phase_patterns

PROFILE = sensor_profile("gelsight_mini")
CONFIG = estimator_config("dis_half")  # cold start: a frame pushed twice gives one answer
PATTERNS = phase_patterns((240, 320))


@pytest.fixture
def estimator(renderer):
    est = estimator_for_sensor(PROFILE, "dis_half")  # cold start: one frame, one answer
    est.set_reference(renderer.render())
    return est


def test_estimator_for_sensor_takes_the_profiles_own_or_the_named_configuration(tmp_path):
    own = estimator_for_sensor("digit")
    assert own.config_name == own.profile.estimator and own.profile.name == "digit"
    assert own.config == estimator_config(own.profile.estimator) and own.calibration is None
    path = tmp_path / "mine.yaml"
    path.write_text((CONFIG_ROOT / "estimators" / "paper.yaml").read_text())
    named = estimator_for_sensor(PROFILE, path, Calibration("gelsight_mini", "mine", {}))
    assert named.config == estimator_config("paper") and named.config_name == str(path)
    assert named.profile is PROFILE and named.calibration.estimator == "mine"
    with pytest.raises(ConfigError, match="sensor 'digit' has none"):
        estimator_for_sensor("digit", "markers")


@pytest.mark.parametrize(
    "pattern,axis,sign",
    [
        ("tilt_x", "tau_x", 1),
        ("tilt_y", "tau_y", 1),
        ("twist", "tau_z", -1),  # the contact turns +z: the gel holds it back, -z
        ("shear", "shear_x", -1),  # the contact moves +x: the gel pulls it back, -x
    ],
)
def test_each_pattern_drives_its_axis_with_the_right_sign(estimator, renderer, pattern, axis, sign):
    for amplitude in (1.0, -1.0):
        e = estimator.push(renderer.render(amplitude * PATTERNS[pattern]), 0.0)
        assert np.sign(getattr(e, axis)) == sign * amplitude
        assert e.contact and not e.zeroing


def test_reference_frame_gives_near_zero_and_no_contact(estimator, renderer):
    e = estimator.push(renderer.render(), 1.0)
    assert not e.contact and e.t_s == 1.0
    assert abs(e.tau_x) < 1e-3 and abs(e.tau_y) < 1e-3


def test_rezero_captures_the_mean_of_n_frames(renderer):
    est = TactileEstimator(CONFIG, PROFILE)
    pressed = renderer.render(PATTERNS["tilt_x"])
    first = est.push(pressed, 0.0)  # no reference yet: starts capturing
    assert first.zeroing and first.tau_x == 0.0
    est.rezero(3)
    for i in range(3):
        assert est.push(pressed, 0.1 * i).zeroing
    assert est.is_zeroed
    after = est.push(pressed, 1.0)  # zeroed on the pressed state: no torque left
    assert abs(after.tau_x) < 1e-3 and not after.zeroing


def test_portrait_frames_are_accepted_when_they_match_the_reference(renderer):
    est = TactileEstimator(CONFIG, PROFILE)
    portrait = np.ascontiguousarray(renderer.render().transpose(1, 0, 2))
    est.set_reference(portrait)
    assert est.field.shape == (16, 12)
    e = est.push(np.ascontiguousarray(renderer.render(PATTERNS["tilt_x"]).transpose(1, 0, 2)), 0)
    assert e.tau_y != 0.0  # the image's x is the rig's y now
    with pytest.raises(ValueError, match="does not match the reference"):
        est.push(renderer.render(), 0.0)


def test_larger_frames_with_the_same_aspect_are_resized(renderer):
    import cv2

    est = TactileEstimator(CONFIG, PROFILE)
    big = cv2.resize(renderer.render(), (640, 480))
    est.set_reference(big)
    assert est.field.shape == (12, 16)


@pytest.mark.parametrize(
    "frame,message",
    [
        (np.zeros((240, 320, 3), np.float32), "uint8"),
        (np.zeros((240, 320, 2), np.uint8), "shape"),
        (np.zeros((100, 320, 3), np.uint8), "does not fit sensor profile"),
    ],
)
def test_bad_frames_are_named(frame, message):
    est = TactileEstimator(CONFIG, PROFILE)
    with pytest.raises(ValueError, match=message):
        est.set_reference(frame)


def test_ema_filter_smooths_a_step(renderer):
    est = TactileEstimator(replace(CONFIG, ema_alpha=0.5), PROFILE)
    est.set_reference(renderer.render())
    est.push(renderer.render(), 0.0)
    pressed = renderer.render(PATTERNS["tilt_x"])
    values = [est.push(pressed, 0.1 * i).tau_x for i in range(1, 8)]
    direct = TactileEstimator(CONFIG, PROFILE)
    direct.set_reference(renderer.render())
    target = direct.push(pressed, 0.0).tau_x
    assert 0.3 * target < values[0] < 0.7 * target
    assert values == sorted(values) and values[-1] == pytest.approx(target, rel=0.02)


def test_calibration_scales_the_output(estimator, renderer):
    pressed = renderer.render(PATTERNS["tilt_x"])
    raw = estimator.push(pressed, 0.0)
    estimator.calibration = Calibration(
        "gelsight_mini", "default", {"tau_x": AxisFit(2e-3, 1e-4, 0.0, 1.0, 10)}
    )
    cal = estimator.push(pressed, 0.0)
    assert cal.calibrated and not raw.calibrated
    assert cal.tau_x == pytest.approx(2e-3 * raw.tau_x + 1e-4)
    assert cal.tau_y == pytest.approx(raw.tau_y)


@pytest.mark.parametrize("divergence_of", ["raw", "curl_free"])
def test_pooled_dipole_equals_the_dipole_on_the_coarser_grid(renderer, divergence_of):
    """The flow pooled over 40 px cells is the 2 x 2 block mean of the 20 px cells' flow, so
    a dipole on an 8 x 6 grid of blocks of the 16 x 12 field is the dipole of an 8 x 6
    estimator."""
    reference, pressed = renderer.render(), renderer.render(PATTERNS["tilt_y"])
    config = replace(CONFIG, divergence_of=divergence_of)
    pooled = TactileEstimator(replace(config, dipole_grid=DipoleGrid(8, 6)), PROFILE)
    coarse = TactileEstimator(replace(config, stride_px=40, dipole_grid=None), PROFILE)
    fine = TactileEstimator(replace(config, dipole_grid=None), PROFILE)
    for est in (pooled, coarse, fine):
        est.set_reference(reference)
    p, c, f = (est.push(pressed, 0.0) for est in (pooled, coarse, fine))
    # equal up to the float32 rounding of the flow pooling
    assert (p.tau_x, p.tau_y) == pytest.approx((c.tau_x, c.tau_y), rel=1e-5, abs=1e-9)
    assert p.tau_y != pytest.approx(f.tau_y, rel=1e-3)  # it is not the fine grid's
    assert p.tau_z == pytest.approx(f.tau_z)  # the NHHD keeps the full grid
    assert pooled.field.shape == (12, 16)


def test_a_non_square_dipole_grid_keeps_the_tilt_signs(renderer):
    """On 4 x 4 blocks of 4 x 3 cells a tilt about y still reads as tau_y of its sign."""
    reference = renderer.render()
    est = TactileEstimator(replace(CONFIG, dipole_grid=DipoleGrid(4, 4)), PROFILE)
    est.set_reference(reference)
    plus = est.push(renderer.render(PATTERNS["tilt_y"]), 0.0)
    minus = est.push(renderer.render(-PATTERNS["tilt_y"]), 0.1)
    assert np.sign(plus.tau_y) == -np.sign(minus.tau_y) != 0
    assert abs(plus.tau_y) > 5 * abs(plus.tau_x)


def test_the_dipole_grid_must_divide_the_field_grid(renderer):
    est = TactileEstimator(replace(CONFIG, dipole_grid=DipoleGrid(5, 4)), PROFILE)
    with pytest.raises(
        ValueError, match="dipole_grid 5 x 4 must divide the estimator grid of 16 x 12"
    ):
        est.set_reference(renderer.render())


@pytest.mark.parametrize("method", ["default", "paper", "markers", "dis_half"])
def test_push_allocates_nothing_of_its_own_per_frame(renderer, method):
    """Steady-state pushes allocate no arrays in our code (only OpenCV's outputs and the
    returned estimate)."""
    est = estimator_for_sensor(PROFILE, method)
    est.set_reference(renderer.render())
    frames = [renderer.render(a * PATTERNS["tilt_x"]) for a in (0.3, 0.6, 0.9)]
    for frame in frames:
        est.push(frame, 0.0)
    ours = str(Path(__file__).resolve().parents[3] / "controller")
    tracemalloc.start()
    try:
        before = tracemalloc.take_snapshot()
        for i in range(30):
            est.push(frames[i % 3], float(i))
        after = tracemalloc.take_snapshot()
    finally:
        tracemalloc.stop()
    grown = [
        stat
        for stat in after.compare_to(before, "lineno")
        if stat.traceback[0].filename.startswith(ours) and stat.size_diff > 0
    ]
    per_frame_bytes = sum(s.size_diff for s in grown) / 30
    # The estimate object itself (~200 B) may remain referenced; array buffers would be KBs.
    assert per_frame_bytes < 512, [str(s) for s in grown[:5]]


@pytest.mark.parametrize("bad", [2.5, float("nan"), 0, -3, True, "3", 10**9])
def test_rezero_refuses_nonsense_and_leaves_the_estimator_usable(estimator, renderer, bad):
    pressed = renderer.render(PATTERNS["tilt_x"])
    before = estimator.push(pressed, 0.0)
    with pytest.raises(ValueError, match="rezero needs a whole number of frames"):
        estimator.rezero(bad)
    assert estimator.is_zeroed
    after = estimator.push(pressed, 0.1)  # no AttributeError, same answer as before
    assert not after.zeroing and after.tau_x == pytest.approx(before.tau_x)


def test_rezero_accepts_numpy_integers(estimator, renderer):
    estimator.rezero(np.int64(2))
    assert estimator.push(renderer.render(), 0.0).zeroing


def test_failed_set_reference_leaves_the_estimator_as_it_was(estimator, renderer):
    pressed = renderer.render(PATTERNS["tilt_x"])
    before = estimator.push(pressed, 0.0)
    half = renderer.render()[::2, ::2].copy()  # 160 x 120: same aspect, another size
    with pytest.raises(ValueError, match="reference frame 1: frame of 160 x 120 px"):
        estimator.set_reference([renderer.render(), half])
    with pytest.raises(ValueError, match="reference frame 0: tactile frame must be"):
        estimator.set_reference([np.zeros((240, 320, 3), np.float32)])
    after = estimator.push(pressed, 0.1)
    assert after.tau_x == pytest.approx(before.tau_x) and estimator.is_zeroed


def test_failed_push_during_zeroing_keeps_the_capture(renderer):
    est = TactileEstimator(CONFIG, PROFILE)
    est.rezero(2)
    assert est.push(renderer.render(), 0.0).zeroing
    with pytest.raises(ValueError, match="does not match the reference"):
        est.push(renderer.render()[::2, ::2].copy(), 0.1)
    assert est.push(renderer.render(), 0.2).zeroing  # the second frame of the two
    assert est.is_zeroed


def test_a_calibration_that_is_not_one_is_refused_at_construction():
    with pytest.raises(
        TypeError, match=r"calibration: expected a Calibration .* got str 'cal\.yaml'"
    ):
        estimator_for_sensor("gelsight_mini", None, "cal.yaml")


@pytest.mark.parametrize(
    "t_s, error, message",
    [
        ("0.84", TypeError, r"t_s: expected a number of seconds, got '0.84'"),
        (True, TypeError, r"t_s: expected a number of seconds"),
        (None, TypeError, r"t_s: expected a number of seconds"),
        (float("nan"), ValueError, r"t_s: expected a finite time in seconds, got nan"),
        (float("inf"), ValueError, r"t_s: expected a finite time in seconds, got inf"),
        (0.5, ValueError, r"t_s: time went backwards, 0.5 s after a frame at 1 s"),
    ],
)
def test_push_refuses_a_time_that_is_not_one_or_goes_backwards(t_s, error, message):
    estimator = estimator_for_sensor("gelsight_mini")
    frame = np.zeros((240, 320, 3), np.uint8)
    estimator.push(frame, 1)
    with pytest.raises(error, match=message):
        estimator.push(frame, t_s)
    estimator.push(frame, np.float32(1.0))  # the same time again, and NumPy numbers, pass
    estimator.set_reference(frame)  # a new reference starts a new recording's times
    estimator.push(frame, 0.0)
