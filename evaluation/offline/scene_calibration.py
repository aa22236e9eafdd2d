"""The estimator's calibration for a task's grasped plug, fitted in the task's simulated
scene the way the paper fits it on the robot: known wrenches on the grasped object, a line
per axis.

``record_in_scene(task, seed)`` builds the task's scene (``drivers.registry``, seeded),
connects its devices and, on the scene's clock:

1. takes the open gel (``capture_open``) while the gripper is open;
2. closes the gripper on the plug with the task's grasp (``machine.gripper``) and lets it
   settle, then zeroes the estimator (``rezero``);
3. records ``rest_s`` at rest: each axis's noise;
4. applies a known wrench to the plug (MuJoCo's ``xfrc_applied`` on the plug's body, at the
   grasp point: the force and torque given in S, turned into B with the plug's pose),
   channel by channel (fx, fy, fz, then the torques about S's x, y, z): a triangle
   0 -> +A -> 0 -> -A -> 0 with ``ramp_s`` per leg, A ``force_n`` or ``torque_nm``.

Every tactile frame of steps 3-4 gives a raw estimate; the scene's truth gives the gel's
wrench on the plug in S (``TruthLog.gel_wrench_s``), minus its value when the reference was
taken (the estimate's zero). ``fit_scene_calibration`` fits each axis of the estimate
against its truth channel (``TRUTH_CHANNEL``; the FingerVision baseline's torques against
the same torques) with ``calibration.fit_axis`` (no intercept), and records each axis's
calibrated noise at rest (``AxisFit.rest_std``), the task and the grasp's fingerprint.
"""

from __future__ import annotations

from collections.abc import Callable
from contextlib import ExitStack
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from controller.run.runner import connect_all
from controller.run.task import Task
from controller.tactile import WrenchSource, estimator_for_sensor
from controller.tactile.calibration import AxisFit, Calibration, estimator_sha256, fit_axis
from controller.tactile.settings import sensor_estimator
from controller.tactile.wrench import VALUE_FIELDS, WrenchEstimate
from core.sensor_profile import sensor_profile
from drivers import registry

TRUTH_CHANNEL = {
    "shear_x": 0,
    "shear_y": 1,
    "normal": 2,
    "tau_x": 3,
    "tau_y": 4,
    "tau_z": 5,
    "fv_tau_x": 3,
    "fv_tau_y": 4,
    "fv_tau_z": 5,
}
"""Each calibrated axis of the estimate -> its column of the true (fx, fy, fz, tau_x, tau_y,
tau_z) gel wrench in S."""

_POLL_S = 0.01
OPEN_GEL_S = 0.5  # the open gel's frames (the estimator takes its default count of them)
_FRAME_MAX_AGE_S = 1.0


@dataclass(frozen=True)
class CalibrationLoads:
    """The known wrench's amplitudes (``force_n`` N, ``torque_nm`` N*m), the time of each leg
    of its triangle (``ramp_s``), the record at rest (``rest_s``) and the grasp's settling
    before zeroing (``settle_s``), s."""

    force_n: float = 1.0
    torque_nm: float = 0.01
    ramp_s: float = 0.5
    rest_s: float = 2.0
    settle_s: float = 0.5

    def __post_init__(self) -> None:
        for name in ("force_n", "torque_nm", "ramp_s", "rest_s", "settle_s"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name}: expected a positive number, got {getattr(self, name)}")

    @property
    def channel_s(self) -> float:
        """The time of one channel's triangle, s."""
        return 4 * self.ramp_s

    def wrench_s(self, t_s: float) -> np.ndarray:
        """The applied wrench (fx, fy, fz N, tau_x, tau_y, tau_z N*m, in S) ``t_s`` seconds
        after the loads began (zero after the last channel)."""
        wrench = np.zeros(6)
        channel, phase = divmod(t_s / self.channel_s, 1.0)
        if 0 <= channel < 6:
            triangle = (
                4 * phase if phase < 0.25 else 2 - 4 * phase if phase < 0.75 else 4 * phase - 4
            )
            wrench[int(channel)] = triangle * (self.force_n if channel < 3 else self.torque_nm)
        return wrench


@dataclass(frozen=True)
class SceneRecording:
    """What ``record_in_scene`` measured: ``t_s`` (n,) the frames' times; ``values`` (n, 9)
    the raw estimates (``VALUE_FIELDS`` order); ``at_rest`` (n,) bool, the frames before the
    loads; ``truth_t_s`` (m,) and ``truth`` (m, 6): the gel's true wrench on the plug in S
    relative to the zeroing's (N, N*m)."""

    t_s: np.ndarray
    values: np.ndarray
    at_rest: np.ndarray
    truth_t_s: np.ndarray
    truth: np.ndarray


SourceFactory = Callable[[Any], WrenchSource]
"""Builds the wrench source to calibrate from the simulated world (the product's: the
task's estimator, uncalibrated; tests inject a source of known gain)."""


def record_in_scene(
    task: Task,
    seed: int = 0,
    loads: CalibrationLoads = CalibrationLoads(),
    source: SourceFactory | None = None,
) -> SceneRecording:
    """Run the calibration in ``task``'s scene (see the module doc)."""
    if task.scene is None:
        raise ValueError(f"{task.path}: the task was loaded without its scene (backend real)")
    config = task.config
    spec = registry.WorldSpec(task.scene, config.plug, config.hole, seed)
    device_set = registry.build_device_set(task.device_files, "sim", spec)
    sim, clock, devices = device_set.world, device_set.clock, device_set.devices
    physics = sim.world.physics
    estimator = (
        estimator_for_sensor(task.tactile_model, config.estimator)
        if source is None
        else source(sim)
    )
    grasp = config.machine.gripper
    with ExitStack() as stack:
        connect_all(devices, stack)
        devices.gripper.activate()
        frames = _FramePump(devices.tactile, estimator, clock)
        estimator.capture_open(None)
        frames.run(OPEN_GEL_S)
        devices.gripper.move(grasp.close_width_m, grasp.close_speed_m_s, grasp.close_force_n)
        _wait(clock, lambda: _held(devices.gripper), 5.0, "the gripper did not hold the plug")
        frames.run(max(loads.settle_s, grasp.settle_s))
        estimator.rezero(None)
        frames.run(5.0, until=lambda e: not e.zeroing)
        sim.sync()
        zero = sim.truth.arrays()["gel_wrench_s"][-1].copy()
        frames.recorded.clear()
        rest_end_s = clock.now() + loads.rest_s
        frames.run(loads.rest_s)
        began_s = clock.now()
        plug = physics.model.body("plug").id
        applied = physics.data.xfrc_applied
        while clock.now() - began_s < 6 * loads.channel_s + loads.ramp_s:
            wrench = loads.wrench_s(clock.now() - began_s)
            applied[plug] = _at_grasp_point_b(physics, plug, wrench)
            frames.step()
        applied[plug] = 0.0
        sim.sync()
        truth = sim.truth.arrays()
    estimates = frames.recorded
    t_s = np.array([e.t_s for e in estimates])
    values = np.array([[getattr(e, name) for name in VALUE_FIELDS] for e in estimates])
    keep = truth["t_s"] >= t_s[0] - 1.0
    return SceneRecording(
        t_s=t_s,
        values=values.reshape(len(t_s), len(VALUE_FIELDS)),
        at_rest=t_s < rest_end_s,
        truth_t_s=truth["t_s"][keep],
        truth=truth["gel_wrench_s"][keep] - zero,
    )


def fit_scene_calibration(recording: SceneRecording, task: Task) -> Calibration:
    """The per-axis fits of ``recording`` (module doc) as ``task``'s calibration file."""
    axes = {}
    rest = recording.values[recording.at_rest]
    for column, axis in enumerate(VALUE_FIELDS):
        fit = fit_axis(
            recording.t_s,
            recording.values[:, column],
            recording.truth_t_s,
            recording.truth[:, TRUTH_CHANNEL[axis]],
        )
        rest_std = float(abs(fit.slope) * rest[:, column].std()) if len(rest) > 1 else None
        axes[axis] = AxisFit(fit.slope, fit.intercept, fit.rmse, fit.r2, fit.samples, rest_std)
    profile = sensor_profile(task.tactile_model)
    name, config = sensor_estimator(profile, task.config.estimator)
    return Calibration(
        sensor=profile.name,
        estimator=name,
        axes=axes,
        estimator_sha256=estimator_sha256(config),
        scene=task.config.task,
        scene_sha256=task.grasp_scene_sha256,
    )


def _at_grasp_point_b(physics: Any, body: int, wrench_s: np.ndarray) -> np.ndarray:
    """``wrench_s`` (in S, about the grasp point: the plug body's origin) as MuJoCo's
    ``xfrc_applied`` row of ``body``: force and torque in B, the torque about the body's
    centre of mass."""
    w, x, y, z = physics.plug_quat()
    s2b = Rotation.from_quat([x, y, z, w])
    force_b, torque_b = s2b.apply(wrench_s[:3]), s2b.apply(wrench_s[3:])
    lever = physics.data.xpos[body] - physics.data.xipos[body]  # centre of mass -> origin
    return np.concatenate([force_b, torque_b + np.cross(lever, force_b)])


def _held(gripper: Any) -> bool:
    status = gripper.read_status()
    return bool(status.holding and not status.moving)


def _wait(clock: Any, done: Callable[[], bool], timeout_s: float, what: str) -> None:
    end_s = clock.now() + timeout_s
    while not done():
        if clock.now() > end_s:
            raise RuntimeError(f"scene calibration: {what} within {timeout_s} s")
        clock.sleep(_POLL_S)


class _FramePump:
    """Pushes each new tactile frame into the source, keeping every estimate."""

    def __init__(self, tactile: Any, source: WrenchSource, clock: Any) -> None:
        self._tactile, self._source, self._clock = tactile, source, clock
        self._last_t_s: float | None = None
        self.recorded: list[WrenchEstimate] = []
        self.latest: WrenchEstimate | None = None

    def step(self) -> None:
        """Advance the clock one poll; push the newest frame if it is new."""
        self._clock.sleep(_POLL_S)
        frame = self._tactile.read_latest(_FRAME_MAX_AGE_S)
        if frame.t_s != self._last_t_s:
            self._last_t_s = frame.t_s
            self.latest = self._source.push(frame.image, frame.t_s)
            self.recorded.append(self.latest)

    def run(self, timeout_s: float, until: Callable[[WrenchEstimate], bool] | None = None) -> None:
        """Step for ``timeout_s`` s, or until an estimate satisfies ``until`` (RuntimeError
        if none does in time)."""
        end_s = self._clock.now() + timeout_s
        while self._clock.now() < end_s:
            self.step()
            if until is not None and self.latest is not None and until(self.latest):
                return
        if until is not None:
            raise RuntimeError(f"scene calibration: the estimator did not zero in {timeout_s} s")
