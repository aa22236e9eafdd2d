"""The calibration fitted in a task's scene (evaluation/offline/scene_calibration.py,
python -m evaluation calibrate_task) and the task's check of it
(controller/run/task_calibration.py):
a source of known gain is recovered; the product's estimator gives the dipole's and the
FingerVision baseline's in-plane torques one sign for one twist; a calibration fitted for
another grasp, estimator or sensor is refused in one line."""

from __future__ import annotations

import numpy as np
import pytest

from controller.run.task import load_task
from controller.tactile.calibration import Calibration
from controller.tactile.wrench import VALUE_FIELDS, WrenchEstimate
from core.config import ConfigError
from evaluation.offline.calibrate_task_cli import main
from evaluation.offline.scene_calibration import (
    TRUTH_CHANNEL,
    CalibrationLoads,
    fit_scene_calibration,
    record_in_scene,
)

LOADS = CalibrationLoads(ramp_s=0.25, rest_s=0.5)
GAIN = {axis: 0.5 + 0.25 * k for k, axis in enumerate(VALUE_FIELDS)}  # truth per raw unit


class KnownGain:
    """A wrench source whose raw estimate of each axis is its true gel wrench divided by
    ``GAIN`` (zeroed as the estimator is: the next frames after ``rezero`` are the zero)."""

    def __init__(self, world) -> None:
        self._physics = world.world.physics
        self._zeroing = 0
        self._zero = np.zeros(6)

    def push(self, frame, t_s: float) -> WrenchEstimate:
        truth = self._physics.gel_wrench_at(t_s)
        if self._zeroing:
            self._zeroing -= 1
            self._zero = truth
            return WrenchEstimate.zero(t_s, zeroing=True, calibrated=False)
        values = {a: (truth - self._zero)[TRUTH_CHANNEL[a]] / GAIN[a] for a in VALUE_FIELDS}
        return WrenchEstimate(t_s, **values, contact=True, degenerate=False,
                              slip_suspected=False, slip_gross=False, rezero_recommended=False,
                              zeroing=False, calibrated=False)  # fmt: skip

    def capture_open(self, n_frames=None) -> None:
        pass

    def rezero(self, n_frames=None) -> None:
        self._zeroing = 3


@pytest.fixture(scope="module")
def usb_c():
    return load_task("usb_c", with_calibration=False)


def test_the_fit_recovers_a_known_gain_on_the_scene(usb_c):
    recording = record_in_scene(usb_c, 0, LOADS, source=KnownGain)
    assert recording.at_rest.any() and (~recording.at_rest).sum() > 50
    calibration = fit_scene_calibration(recording, usb_c)
    for axis, gain in GAIN.items():
        fit = calibration.axes[axis]
        assert fit.slope == pytest.approx(gain, rel=0.02), axis
        assert fit.r2 > 0.99, axis
    assert calibration.scene == "usb_c"
    assert calibration.scene_sha256 == usb_c.grasp_scene_sha256


def test_the_estimator_gives_one_sign_for_one_twist_in_both_methods(usb_c):
    """The known twist about S z moves the dipole/NHHD tau_z and the FingerVision fv_tau_z
    the same way (each fit's slope is positive: the raw torque follows the true one)."""
    calibration = fit_scene_calibration(record_in_scene(usb_c, 0, LOADS), usb_c)
    tau_z, fv_tau_z = calibration.axes["tau_z"], calibration.axes["fv_tau_z"]
    assert tau_z.slope > 0 and fv_tau_z.slope > 0
    # linear too: R^2 0.94 on these short ramps with the scene's camera latency, jitter and
    # blur (0.98 for both in the shipped fit, configs/calibrations/usb_c.yaml)
    assert tau_z.r2 > 0.9 and fv_tau_z.r2 > 0.9
    assert calibration.axes["tau_x"].r2 > 0.9  # the dipole's tilt about the plug's width
    assert all(fit.rest_std is not None and fit.rest_std >= 0 for fit in calibration.axes.values())


def test_the_shipped_calibrations_fit_their_tasks():
    for name in ("usb_a", "usb_c"):
        task = load_task(name)
        assert task.calibration is not None and task.calibration.scene == name


@pytest.mark.parametrize(
    "override,reason",
    [
        ("scene.gel_spring.stiffness_n_m=30000.0", "fitted in another scene"),
        ("scene.tactile_appearance=speckle", "fitted in another scene"),
        ("plug.length_m=0.021", "fitted in another scene"),
        ("estimator=paper", "estimator configuration"),
    ],
)
def test_a_calibration_for_another_grasp_or_estimator_is_one_line(override, reason):
    with pytest.raises(ConfigError) as error:
        load_task("usb_c", [override])
    message = str(error.value)
    assert "\n" not in message and reason in message
    assert "key 'calibration'" in message and "evaluation calibrate_task --task usb_c" in message


def test_a_search_setting_keeps_the_calibration():
    task = load_task("usb_c", ["scene.hole_uncertainty.yaw_rad=0.0", "scene.friction=0.5"])
    assert task.calibration is not None


def test_a_missing_calibration_file_is_one_line(tmp_path):
    refit = "does not exist; re-run python -m evaluation calibrate_task"
    with pytest.raises(ConfigError, match=refit):
        load_task("usb_c", [f"calibration={tmp_path / 'none.yaml'}"])


def test_the_tool_writes_a_calibration_the_task_accepts(tmp_path, capsys):
    out = tmp_path / "usb_c.yaml"
    assert main(["--task", "usb_c", "--out", str(out)]) == 0
    assert "| tau_z |" in capsys.readouterr().out
    written = Calibration.load(out)
    assert load_task("usb_c", [f"calibration={out}"]).calibration == written


def test_the_tool_refuses_a_folder_before_any_work(tmp_path, capsys):
    assert main(["--task", "usb_c", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("calibrate_task: error: --out") and "\n" not in err
