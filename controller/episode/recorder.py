"""What feeds an episode during a run: ``TickLogger``, the control loop's observer (each
tick's command, statuses, teleop, timing, TCP pose, phase changes and in-hand estimates), and
``RecordingSource``, a tap on the wrench source (each frame as the estimator received it,
the field, the estimate, and the calls that change the estimator's reference).

Both only enqueue (``EpisodeWriter.log``): the payloads are the loop's own immutable records
(and a copy of each frame), turned into bytes on the writer's thread by the functions here.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from typing import Any, Protocol, cast

import numpy as np
from scipy.spatial.transform import Rotation

from controller.episode import foxglove_types, topics
from controller.episode.writer import EpisodeWriter, json_bytes
from controller.insertion.interface import InHandEstimate, TeleopInput
from controller.insertion.machine_config import s2t_matrix
from controller.loop import TickRecord
from controller.tactile.estimator import TactileEstimator
from controller.tactile.field import VectorField
from controller.tactile.wrench import FLAG_FIELDS, VALUE_FIELDS, WrenchEstimate
from controller.tactile.wrench_source import WrenchSource, estimator_of
from core.clock import Clock
from core.devices import ArmStatus, GripperStatus, Twist
from core.spatial import quat_from_rpy

# -- the tick's messages (encoded on the writer's thread) ----------------------------------


def command_json(tick: TickRecord) -> bytes:
    command = tick.command
    twist = command.twist if command is not None else None
    pose = command.pose if command is not None else None
    gripper = command.gripper if command is not None else None
    return json_bytes(
        {
            "twist_linear_m_s": twist.linear_m_s if twist else None,
            "twist_angular_rad_s": twist.angular_rad_s if twist else None,
            "pose_xyz_m": pose.xyz_m if pose else None,
            "pose_rpy_rad": pose.rpy_rad if pose else None,
            "gripper_width_m": gripper.width_m if gripper else None,
            "gripper_speed_m_s": gripper.speed_m_s if gripper else None,
            "gripper_force_n": gripper.force_n if gripper else None,
            "capture_open_tactile": bool(command and command.capture_open_tactile),
            "rezero_tactile": bool(command and command.rezero_tactile),
            "limited": list(tick.limited),
            "rule": command.rule if command is not None else "",
            "stage": command.stage if command is not None else "",
            "sent": command is not None,
            "fault": tick.fault,
        }
    )


def finite(values: tuple[float, ...]) -> tuple[float, ...] | None:
    """``values``, or None when one is NaN or infinite (a simulated arm's joint angles): the
    key ``json_bytes`` would leave out, left out before the encoding (no second pass)."""
    return values if math.isfinite(sum(values)) else None


def arm_json(arm: ArmStatus) -> bytes:
    return json_bytes(
        {
            "t_s": arm.t_s,
            "tcp_xyz_m": arm.tcp.xyz_m,
            "tcp_rpy_rad": arm.tcp.rpy_rad,
            "joints_rad": finite(arm.joints_rad),
            "mode": arm.mode.name.lower(),
            "state": arm.state.name.lower(),
            "error_code": arm.error_code,
            "warning_code": arm.warning_code,
            "external_force_n": arm.external_force_n,
        }
    )


def gripper_json(gripper: GripperStatus) -> bytes:
    return json_bytes(
        {
            "t_s": gripper.t_s,
            "activated": gripper.activated,
            "moving": gripper.moving,
            "object": gripper.object.name.lower(),
            "width_m": gripper.width_m,
            "fault_code": gripper.fault_code,
            "fault_message": gripper.fault_message,
        }
    )


def teleop_json(teleop: TeleopInput) -> bytes:
    twist: Twist = teleop.twist
    return json_bytes(
        {
            "connected": teleop.connected,
            "in_control": teleop.in_control,
            "in_control_by": "operator" if teleop.in_control else "machine",
            "twist_linear_m_s": twist.linear_m_s,
            "twist_angular_rad_s": twist.angular_rad_s,
            "gripper_open": teleop.gripper_open,
            "gripper_close": teleop.gripper_close,
            "hand_back": teleop.hand_back,
            "estop": teleop.estop,
            "estop_ack": teleop.estop_ack,
            "deadman": teleop.deadman,
        }
    )


def tick_json(tick: TickRecord) -> bytes:
    timing = tick.timing
    return json_bytes(
        {
            "index": timing.index,
            "deadline_s": timing.deadline_s,
            "start_s": timing.start_s,
            "end_s": timing.end_s,
            "overran": timing.overran,
            "phase": tick.phase.value,
            "fault": tick.fault,
        }
    )


def tcp_tf(arm: ArmStatus, offset_ns: int = 0) -> bytes:
    quaternion = quat_from_rpy(arm.tcp.rpy_rad)
    return foxglove_types.transforms_bytes(
        arm.t_s, [("B", "T", arm.tcp.xyz_m, quaternion)], offset_ns
    )


Mount = tuple[tuple[float, float, float], tuple[float, float, float, float]]
"""Where the sensor sits on the tool: S's origin in T (m) and the S2T rotation as a
quaternion (x, y, z, w)."""


def sensor_mount(torque_axes: tuple[str, str, str], plug_thickness_m: float) -> Mount:
    """S in T (``/tf_static``): the rotation of the machine's ``signals.torque_axes`` (S's axes
    as signed axes of T) and the origin at the gel's centre, on the plug's face half its
    thickness along +y_T from the TCP (drivers/sim/scenes/insertion/frames.py)."""
    quat = Rotation.from_matrix(s2t_matrix(torque_axes)).as_quat()  # (x, y, z, w)
    x, y, z, w = (float(v) for v in quat)
    return (0.0, 0.5 * float(plug_thickness_m), 0.0), (x, y, z, w)


def static_tf(item: tuple[float, Mount], offset_ns: int = 0) -> bytes:
    t_s, (origin, quaternion) = item
    return foxglove_types.transforms_bytes(t_s, [("T", "S", origin, quaternion)], offset_ns)


def transition_json(transition: Any) -> bytes:
    return json_bytes(
        {
            "t_s": transition.t_s,
            "from": transition.source.value,
            "to": transition.target.value,
            "reason": transition.reason,
            "rule": transition.rule,
        }
    )


def grasp_estimate_json(estimate: InHandEstimate) -> bytes:
    return json_bytes(
        {
            "t_s": estimate.t_s,
            "plane": estimate.plane,
            "tilt_rad": estimate.tilt_rad,
            "tip_offset_m": estimate.tip_offset_m,
            "method": estimate.method,
            "kept": bool(estimate.kept),
        }
    )


LATCH_PERIOD_S = 1.0
"""A latched topic (``/gripper/status``, ``/teleop/input``) is written when its value changes,
and otherwise again at the first tick this long after the last one written, s of loop time
(controller/episode/topics.py)."""


TF_PERIOD_S = 0.035
"""``/tf`` and ``/sim/tf`` are written at the first tick (truth row) this long or more after
the last one written, s of loop time: every 4th tick of the 100 Hz loop (25 Hz, the
camera's rate), enough for the 3D view (which places a message by the newest transform at
or before its time); the pose at every tick is ``/arm/status`` (and ``/sim/truth``). A
period short of 0.04 s, so a tick's time that float rounding puts a hair early is not
skipped."""


class Latch:
    """When a slowly changing value is due in the file: the first time, whenever ``key``
    differs from the last one written, and otherwise once ``period_s`` (s on the loop's
    clock) has passed since the last one written. With a constant ``key`` (None), a
    throttle: at most one per ``period_s``."""

    def __init__(self, period_s: float = LATCH_PERIOD_S) -> None:
        self.period_s = period_s
        self._key: object = None
        self._due_s = -math.inf

    def due(self, key: object, t_s: float) -> bool:
        if t_s < self._due_s and key == self._key:
            return False
        self._key, self._due_s = key, t_s + self.period_s
        return True


def gripper_key(gripper: GripperStatus) -> tuple:
    """What makes a gripper status a change: every field but its read time."""
    g = gripper
    return (g.activated, g.moving, g.object, g.width_m, g.fault_code, g.fault_message)


class TickLogger:
    """The loop's observer: queues each tick's messages into ``writer`` (the latched topics
    only when due, see ``Latch``; ``/tf`` every ``TF_PERIOD_S``; ``/tf_static`` with
    ``mount``, where the sensor sits on the tool, when given), then wakes the writer if a
    flush is due, at once at each phase change."""

    def __init__(self, writer: EpisodeWriter, mount: Mount | None = None) -> None:
        self.writer = writer
        self.mount = mount
        self._gripper = Latch()
        self._teleop = Latch()
        self._static = Latch()
        self._tf = Latch(TF_PERIOD_S)
        self._tcp_tf = functools.partial(tcp_tf, offset_ns=writer.offset_ns)
        self._static_tf = functools.partial(static_tf, offset_ns=writer.offset_ns)

    def __call__(self, tick: TickRecord) -> None:
        log, t = self.writer.log, tick.timing.start_s
        obs = tick.observation
        log(topics.COMMAND, t, command_json, tick)
        log(topics.ARM_STATUS, t, arm_json, obs.arm)
        if self._gripper.due(gripper_key(obs.gripper), t):
            log(topics.GRIPPER_STATUS, t, gripper_json, obs.gripper)
        if self._teleop.due(obs.teleop, t):
            log(topics.TELEOP, t, teleop_json, obs.teleop)
        log(topics.LOOP_TICK, t, tick_json, tick)
        if self._tf.due(None, t):
            log(topics.TCP_TF, t, self._tcp_tf, obs.arm)
        if self.mount is not None and self._static.due(self.mount, t):
            log(topics.TF_STATIC, t, self._static_tf, (t, self.mount))
        for transition in tick.transitions:
            log(topics.TRANSITION, transition.t_s, transition_json, transition)
        for estimate in tick.in_hand_estimates:
            log(topics.GRASP_ESTIMATE, estimate.t_s, grasp_estimate_json, estimate)
        if tick.transitions:
            self.writer.flush_soon()
        self.writer.flush_if_due()


# -- the tactile tap -----------------------------------------------------------------------


def wrench_json(item: tuple[int, WrenchEstimate]) -> bytes:
    index, e = item
    row: dict[str, Any] = {"t_s": e.t_s, "push_index": index}
    row.update({k: getattr(e, k) for k in VALUE_FIELDS})
    row.update({k: bool(getattr(e, k)) for k in FLAG_FIELDS})
    return json_bytes(row)


def call_json(row: dict[str, Any]) -> bytes:
    return json_bytes(row)


def field_of(estimator: TactileEstimator | None) -> VectorField | None:
    """``estimator``'s latest displacement field, None without one."""
    if estimator is None:
        return None
    try:
        return estimator.field
    except RuntimeError:  # no reference yet
        return None


class CompressingCamera(Protocol):
    """A tactile camera that can hand its frames over compressed too (the GelSight/DIGIT
    driver and its simulated twin): ``TactileFrame.jpeg``."""

    def compress_frames(self, encode: Callable[[np.ndarray], bytes] | None) -> None: ...

    def compressed(self, image: np.ndarray) -> bytes | None: ...


class RecordingSource:
    """A ``WrenchSource`` that passes every call to ``source`` and queues into ``writer``:
    each frame, the field after it (if the estimator has one), the estimate it gave, and the
    calls in order (``/tactile/push``), each logged at ``clock.now()``.

    The frame is logged as ``image_format`` 'jpeg' or 'png'. With a ``camera`` that
    compresses (``CompressingCamera``) and 'jpeg', the camera is given the writer's own JPEG
    encoder at ``jpeg_quality`` (``foxglove_types.encode_image``) to run on each frame, and the
    writer logs those bytes as they come; a frame the camera did not compress (none, or not
    the image it handed over last) is copied and encoded on the writer's thread."""

    def __init__(
        self,
        source: WrenchSource,
        writer: EpisodeWriter,
        clock: Clock,
        *,
        image_format: str = "jpeg",
        jpeg_quality: int = 80,
        camera: object = None,
    ) -> None:
        if image_format not in ("jpeg", "png"):
            raise ValueError(f"image_format: expected 'jpeg' or 'png', got {image_format!r}")
        self.source = source
        self.writer = writer
        self.clock = clock
        self.image_format = image_format
        self.jpeg_quality = jpeg_quality
        self._pushes = 0
        self._estimator = estimator_of(source)
        self._compressed: Callable[[np.ndarray], bytes | None] | None = None
        if image_format == "jpeg" and hasattr(camera, "compress_frames"):
            compressing = cast(CompressingCamera, camera)
            compressing.compress_frames(
                functools.partial(
                    foxglove_types.encode_image, image_format="jpeg", jpeg_quality=jpeg_quality
                )
            )
            self._compressed = compressing.compressed

    @property
    def estimator(self) -> WrenchSource:
        """The wrapped source (wrappers are walked through ``.estimator``)."""
        return self.source

    def push(self, frame: np.ndarray, t_s: float) -> WrenchEstimate:
        estimate = self.source.push(frame, t_s)
        index = self._pushes
        self._pushes += 1
        now = self.clock.now()
        log = self.writer.log
        log(
            topics.TACTILE_PUSH,
            now,
            call_json,
            {"call": "push", "push_index": index, "frame_t_s": float(t_s)},
        )
        jpeg = self._compressed(frame) if self._compressed is not None else None
        image = frame.copy() if jpeg is None else jpeg
        log(topics.TACTILE_IMAGE, now, self._image_bytes, (float(t_s), image))
        field = field_of(self._estimator)
        if field is not None and not estimate.zeroing:
            log(topics.TACTILE_FIELD, now, self._grid_bytes, (float(t_s), field))
        log(topics.TACTILE_WRENCH, now, wrench_json, (index, estimate))
        return estimate

    def capture_open(self, n_frames: int | None = None) -> None:
        self.source.capture_open(n_frames)
        self._log_call("capture_open", n_frames)

    def rezero(self, n_frames: int | None = None) -> None:
        self.source.rezero(n_frames)
        self._log_call("rezero", n_frames)

    def _log_call(self, call: str, n_frames: int | None) -> None:
        row = {"call": call, "push_index": self._pushes, "n_frames": n_frames}
        self.writer.log(topics.TACTILE_PUSH, self.clock.now(), call_json, row)

    def _image_bytes(self, item: tuple[float, np.ndarray | bytes]) -> bytes:
        t_s, image = item
        return foxglove_types.image_bytes(
            t_s, image, self.image_format, self.jpeg_quality, self.writer.offset_ns
        )

    def _grid_bytes(self, item: tuple[float, VectorField]) -> bytes:
        return foxglove_types.grid_bytes(*item, offset_ns=self.writer.offset_ns)
