"""The torques on the plug as it goes in, scored from the scene's truth."""

import math

import numpy as np
import pytest

from evaluation.trials.entry_torque import entry_torques


def _truth(depth_mm, contact, torque_mnm):
    n = len(depth_mm)
    wrench = np.zeros((n, 6))
    wrench[:, 3:6] = np.asarray(torque_mnm, dtype=float) * 1e-3
    return {
        "t_s": np.arange(n) * 0.1,
        "depth_m": np.asarray(depth_mm, dtype=float) * 1e-3,
        "contact_force_n": np.asarray(contact, dtype=float),
        "gel_wrench_s": wrench,
    }


HOLD = [5.0, -2.0, 1.0]  # the grip's moment in the air, mN*m


def test_the_change_from_the_hold_over_the_entry_only():
    depth = [0, 0, 0, 0, 0.5, 1.0, 3.0, 5.0]
    contact = [0, 0, 0, 0, 1, 1, 1, 1]
    torque = [HOLD] * 4 + [[50, 50, 50], [8, -6, 1], [5, -2, 7], [90, 90, 90]]
    tilt, inplane = entry_torques(_truth(depth, contact, torque), depth_m=0.005)
    # the rows 1 mm and 3 mm in (the press before and the row at the depth left out)
    assert tilt == pytest.approx(math.sqrt((5.0**2 + 0.0) / 2) * 1e-3)
    assert inplane == pytest.approx(math.sqrt((0.0 + 6.0**2) / 2) * 1e-3)


def test_a_plug_that_never_entered_reads_unknown():
    depth = [0, 0, 0.5, 0.2]
    tilt, inplane = entry_torques(_truth(depth, [0, 0, 1, 1], [HOLD] * 4), depth_m=0.005)
    assert math.isnan(tilt) and math.isnan(inplane)


def test_no_hold_in_the_air_reads_unknown():
    depth = [0, 2.0, 3.0]
    tilt, _ = entry_torques(_truth(depth, [1, 1, 1], [HOLD] * 3), depth_m=0.005)
    assert math.isnan(tilt)
