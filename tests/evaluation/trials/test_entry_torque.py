"""The torques on the plug as it goes in, scored from the scene's truth."""

import math

import numpy as np
import pytest

from controller.run.result import TrialResult
from evaluation.trials.entry_torque import entry_torques
from evaluation.trials.summary import summarize


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


def _result(seed, tilt, inplane):
    return TrialResult(
        task="usb_c", controller="dipole", seed=seed, success=True, status="inserted",
        failure_reason=None, time_to_insert_s=5.0, duration_s=8.0, max_wrist_force_n=2.0,
        force_limit_n=20.0, wall_time_s=1.0, entry_tilt_torque_rms_nm=tilt,
        entry_inplane_torque_rms_nm=inplane,
    )  # fmt: skip


def test_the_summary_takes_the_median_of_the_trials_that_entered():
    s = summarize(
        [_result(0, 0.002, 0.001), _result(1, 0.006, 0.003), _result(2, math.nan, math.nan)]
    )
    assert s["entry_tilt_torque_median_nm"] == pytest.approx(0.004)
    assert s["entry_inplane_torque_median_nm"] == pytest.approx(0.002)
    none = summarize([_result(0, math.nan, math.nan)])
    assert none["entry_tilt_torque_median_nm"] is None
