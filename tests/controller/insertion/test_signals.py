"""The machine's tactile signals: baseline after zeroing, noise units, filtering, new samples."""

import numpy as np
import pytest

from controller.insertion.machine_config import NoiseFloor, SignalSettings
from controller.insertion.signals import TactileSignals
from controller.tactile.wrench import WrenchEstimate
from tests.controller.insertion.world import TOY_FLOOR, estimate


def zeroing(t_s):
    return WrenchEstimate.zero(t_s, zeroing=True, calibrated=False)


def settings(**kw):
    kw.setdefault("noise_floor", TOY_FLOOR)  # the figures below assume it
    return SignalSettings(baseline_frames=4, ema_alpha=1.0, **kw)


def test_baseline_needs_a_zeroing_first_and_ignores_stale_estimates():
    signals = TactileSignals(settings())
    signals.reset()
    assert not signals.update(estimate(0.0, tau_x=5.0))  # stale: before the zeroing
    assert not signals.update(zeroing(0.1))
    for i in range(4):
        assert not signals.update(estimate(0.2 + 0.1 * i, tau_x=0.01 * (-1) ** i))
    assert signals.ready
    assert signals.update(estimate(1.0, tau_x=0.01))
    # mean 0, std 0.01 (above the 0.0002 floor): 0.01 is one noise unit
    assert signals.normalised[0] == pytest.approx(1.0)


def test_a_repeated_estimate_is_not_a_new_sample():
    signals = TactileSignals(settings())
    for i in range(4):
        signals.update(estimate(0.1 * i))
    same = estimate(1.0, normal=1.0)
    assert signals.update(same)
    assert not signals.update(same)


def test_noise_floor_bounds_the_noise_and_units_follow_the_channel():
    floor = NoiseFloor(
        tilt_x=0.001, tilt_y=0.001, inplane=0.01, shear_x=0.002, shear_y=0.002, normal=0.004
    )
    signals = TactileSignals(settings(noise_floor=floor))
    for i in range(4):
        signals.update(estimate(0.1 * i))  # noise-free baseline: the floors apply
    signals.update(estimate(1.0, tau_x=0.002, tau_z=0.02, shear_y=0.004, normal=0.004))
    np.testing.assert_allclose(signals.normalised, [2, 0, 2, 0, 2, 1])
    assert signals.magnitude == pytest.approx(np.sqrt(13))
    np.testing.assert_allclose(signals.deviation, [0.002, 0, 0.02, 0, 0.004, 0.004])


def test_moving_average_weights_new_samples_by_alpha():
    signals = TactileSignals(
        SignalSettings(baseline_frames=2, ema_alpha=0.25, noise_floor=TOY_FLOOR)
    )
    signals.update(estimate(0.0))
    signals.update(estimate(0.1))
    signals.update(estimate(0.2, shear_y=0.002))  # one noise unit (floor)
    assert signals.normalised[4] == pytest.approx(0.25)
    signals.update(estimate(0.3, shear_y=0.002))
    assert signals.normalised[4] == pytest.approx(0.25 + 0.75 * 0.25)


def test_torques_and_axial_force_in_the_tool_frame():
    signals = TactileSignals(settings())  # S x = T x, S y = T z, S z = -T y
    for i in range(4):
        signals.update(estimate(0.1 * i))
    signals.update(estimate(1.0, tau_x=0.0002, tau_y=0.0004, tau_z=0.005, shear_y=0.3))
    np.testing.assert_allclose(signals.torque_t, [1.0, -1.0, 2.0])
    assert signals.axial_force == pytest.approx(0.3)  # shear along S y = along T z
    assert signals.axial_force_sigma == pytest.approx(150.0)


def test_reset_forgets_the_baseline():
    signals = TactileSignals(settings())
    for i in range(4):
        signals.update(estimate(0.1 * i))
    assert signals.ready
    signals.reset()
    assert not signals.ready and signals.magnitude == 0.0
    np.testing.assert_array_equal(signals.deviation, np.zeros(6))
