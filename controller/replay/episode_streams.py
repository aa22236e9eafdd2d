"""An episode's streams as arrays: what the replay tools (summary, chart, re-estimation,
LeRobot export) read from an ``Episode`` (controller/episode, docs/EPISODES.md).

Times are s on the loop's clock: a tick's is its messages' log time; an estimate's is its
frame's capture time (``t_s``). Missing numbers (a null in the file) are NaN.

A message without a field these functions need, or with a value of the wrong type (a
hand-made file, another program's), is an ``EpisodeError`` naming the file, the function's
streams and the field: one line, never a traceback.
"""

from __future__ import annotations

import functools
import json
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any, TypeVar

import numpy as np

from controller.episode import Episode, EpisodeError, decode_image
from controller.episode.foxglove_types import loop_time_s
from controller.episode.topics import (
    ARM_STATUS,
    COMMAND,
    DROPS,
    GRASP_ESTIMATE,
    GRIPPER_STATUS,
    LOOP_TICK,
    SIM_TF,
    SIM_TRUTH,
    TACTILE_IMAGE,
    TACTILE_PUSH,
    TACTILE_WRENCH,
    TRANSITION,
)
from controller.replay.trial_chart import ChartTruth
from controller.tactile.wrench import VALUE_FIELDS

HOLE_FRAME = "H"
"""The true hole's child frame on ``/sim/tf``."""

_Result = TypeVar("_Result")
_Value = TypeVar("_Value")


def _fields_checked(what: str) -> Callable[[Callable[..., _Result]], Callable[..., _Result]]:
    """Turn a missing field or a wrong type in ``what`` (the streams read) into one
    ``EpisodeError`` line naming the episode (see the module doc)."""

    def decorate(function: Callable[..., _Result]) -> Callable[..., _Result]:
        @functools.wraps(function)
        def checked(episode: Episode, *args: Any, **kwargs: Any) -> _Result:
            try:
                return function(episode, *args, **kwargs)
            except EpisodeError:
                raise
            except (KeyError, TypeError, ValueError, IndexError, AttributeError) as error:
                detail = f"no field {error}" if isinstance(error, KeyError) else str(error)
                raise EpisodeError(
                    f"episode '{episode.path}': {what}: a message lacks what this package's "
                    f"writer writes ({type(error).__name__}: {' '.join(detail.split())[:160]})"
                ) from None

        return checked

    return decorate


def _number(value: object) -> float:
    return np.nan if value is None else float(value)  # type: ignore[arg-type]


def _vector(value: object, width: int) -> list[float]:
    return [np.nan] * width if value is None else [_number(v) for v in value]  # type: ignore[attr-defined]


def _typed(value: object, kind: type[_Value], name: str) -> _Value:
    """``value`` if it is a ``kind``; TypeError naming the field ``name`` otherwise (an
    absent field reads as None)."""
    if not isinstance(value, kind):
        raise TypeError(f"field {name!r}: expected {kind.__name__}, got {value!r}")
    return value


@dataclass(frozen=True)
class Ticks:
    """One row per control tick, from the messages logged every tick: ``t_s`` (n,),
    ``phase`` (the machine's phase after its step), the arm's TCP ``tcp_xyz_m`` and
    ``tcp_rpy_rad`` (n, 3: T2B), the gripper's ``gripper_width_m`` (n,), the command as
    sent: ``twist`` (n, 6: linear m/s, angular rad/s in B; NaN where none was sent) and
    ``gripper_target_m`` (n,: the opening last commanded, NaN before the first), and the
    ``limited`` names of each tick."""

    t_s: np.ndarray
    phase: list[str]
    tcp_xyz_m: np.ndarray
    tcp_rpy_rad: np.ndarray
    gripper_width_m: np.ndarray
    twist: np.ndarray
    gripper_target_m: np.ndarray
    limited: list[list[str]]

    def __len__(self) -> int:
        return len(self.t_s)


@_fields_checked("/loop/tick, /arm/status, /gripper/status, /control/command")
def ticks(episode: Episode) -> Ticks:
    """The episode's ticks: times (each tick's start) and phases from ``/loop/tick``, the
    state and command of the same log time from ``/arm/status``, ``/gripper/status`` and
    ``/control/command`` (a tick whose message is missing, e.g. dropped, holds the previous
    value)."""
    loop = [(m.t_s, m.value) for m in episode.messages(LOOP_TICK.name)]
    arm = {m.t_s: m.value for m in episode.messages(ARM_STATUS.name)}
    gripper = {m.t_s: m.value for m in episode.messages(GRIPPER_STATUS.name)}
    command = {m.t_s: m.value for m in episode.messages(COMMAND.name)}
    xyz, rpy, width, twist, target, limited = [], [], [], [], [], []
    last_arm: dict = {"tcp_xyz_m": None, "tcp_rpy_rad": None}
    last_gripper: dict = {"width_m": None}
    held_target = np.nan
    for time_s, _ in loop:
        last_arm = arm.get(time_s, last_arm)
        last_gripper = gripper.get(time_s, last_gripper)
        sent = command.get(time_s, {})
        xyz.append(_vector(last_arm["tcp_xyz_m"], 3))
        rpy.append(_vector(last_arm["tcp_rpy_rad"], 3))
        width.append(_number(last_gripper["width_m"]))
        if sent.get("twist_linear_m_s") is not None and sent.get("sent", True):
            twist.append(_vector(sent["twist_linear_m_s"], 3)
                         + _vector(sent["twist_angular_rad_s"], 3))  # fmt: skip
        else:
            twist.append([np.nan] * 6)
        if sent.get("gripper_width_m") is not None and sent.get("sent", True):
            held_target = float(sent["gripper_width_m"])
        target.append(held_target)
        limited.append(list(sent.get("limited", [])))
    return Ticks(
        np.array([tick["start_s"] for _, tick in loop], dtype=float),
        [tick["phase"] for _, tick in loop],
        np.array(xyz, dtype=float).reshape(-1, 3),
        np.array(rpy, dtype=float).reshape(-1, 3),
        np.array(width, dtype=float),
        np.array(twist, dtype=float).reshape(-1, 6),
        np.array(target, dtype=float),
        limited,
    )


@dataclass(frozen=True)
class Estimates:
    """The logged estimates, one per frame pushed: ``push_index`` (n,), ``t_s`` (n,: the
    frame's capture time), ``values`` (n, len(VALUE_FIELDS): raw, NaN where null), the
    ``contact`` flags and the ``zeroing`` flags (n,: no reference yet, values all 0);
    ``calibrated``: every estimate after zeroing is in N*m and N; ``tick_t_s`` (n,: the
    time of the tick that made it, the message's log time; empty when not given)."""

    push_index: np.ndarray
    t_s: np.ndarray
    values: np.ndarray
    contact: np.ndarray
    zeroing: np.ndarray
    calibrated: bool = False
    tick_t_s: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def column(self, name: str) -> np.ndarray:
        return self.values[:, VALUE_FIELDS.index(name)]


@_fields_checked("/tactile/wrench")
def estimates(episode: Episode) -> Estimates:
    """The ``/tactile/wrench`` messages as arrays."""
    messages = list(episode.messages(TACTILE_WRENCH.name))
    rows = [m.value for m in messages]
    return Estimates(
        np.array([r["push_index"] for r in rows], dtype=int),
        np.array([r["t_s"] for r in rows], dtype=float),
        np.array([[_number(r.get(k)) for k in VALUE_FIELDS] for r in rows]).reshape(
            -1, len(VALUE_FIELDS)
        ),
        np.array([bool(r.get("contact", False)) for r in rows]),
        np.array([bool(r.get("zeroing", False)) for r in rows]),
        any(not r.get("zeroing") for r in rows)
        and all(r.get("calibrated", False) for r in rows if not r.get("zeroing")),
        np.array([m.t_s for m in messages], dtype=float),
    )


@dataclass(frozen=True)
class SourceCall:
    """One call the loop made into the wrench source (``/tactile/push``): ``call`` ('push',
    'capture_open' or 'rezero'), ``push_index``, ``frame_t_s`` (pushes), ``n_frames``
    (the others; None: the source's default)."""

    call: str
    push_index: int
    frame_t_s: float | None
    n_frames: int | None


@_fields_checked("/tactile/push")
def source_calls(episode: Episode) -> list[SourceCall]:
    """The calls into the wrench source, in the order made."""
    return [
        SourceCall(v["call"], int(v["push_index"]), v.get("frame_t_s"), v.get("n_frames"))
        for v in (m.value for m in episode.messages(TACTILE_PUSH.name))
    ]


@dataclass(frozen=True)
class LoggedFrame:
    """A tactile frame as logged: ``t_s`` (when pushed, the tick's time), ``capture_t_s``
    and ``image_format`` ('png': the pixels the estimator took; 'jpeg': lossy)."""

    t_s: float
    capture_t_s: float
    image_format: str
    _value: object

    def image(self) -> np.ndarray:
        """The image as the estimator took it: uint8 BGR (H x W x 3) or grey (H x W)."""
        return decode_image(self._value)


def frames(episode: Episode) -> Iterator[LoggedFrame]:
    """The ``/tactile/image`` frames in the order pushed, decoded only when asked."""
    for message in episode.messages(TACTILE_IMAGE.name):
        stamp = message.value.timestamp  # a protobuf message: always there
        capture = loop_time_s(stamp, episode.offset_ns)  # stamped on the log times' clock
        yield LoggedFrame(message.t_s, capture, message.value.format, message.value)


@dataclass(frozen=True)
class Transition:
    t_s: float
    source: str
    target: str
    reason: str
    rule: str = ""  # which of the guard's rules fired ("" in files from before the field)


@_fields_checked("/machine/transition")
def transitions(episode: Episode) -> list[Transition]:
    """The machine's phase changes with their reasons and rules."""
    return [
        Transition(v["t_s"], v["from"], v["to"], v["reason"], v.get("rule", ""))
        for v in (m.value for m in episode.messages(TRANSITION.name))
    ]


@dataclass(frozen=True)
class GraspEstimate:
    """One ``/machine/grasp_estimate`` message: the plug's tilt in the hand in ``plane``
    ('thickness' about T x, 'width' about T y; rad) estimated at ``t_s``, the tip's offset
    it implies (m, along T y or T x; NaN where the file has none), how (``method``) and
    whether the machine kept it."""

    t_s: float
    plane: str
    tilt_rad: float
    tip_offset_m: float
    method: str
    kept: bool


@_fields_checked("/machine/grasp_estimate")
def grasp_estimates(episode: Episode) -> list[GraspEstimate]:
    """The machine's estimates of the plug in the hand, in the order made (none in a file
    from before the topic, or of a run whose machine made none)."""
    return [
        GraspEstimate(
            float(v["t_s"]),
            _typed(v["plane"], str, "plane"),
            _number(v.get("tilt_rad")),
            _number(v.get("tip_offset_m")),
            _typed(v["method"], str, "method"),
            _typed(v["kept"], bool, "kept"),
        )
        for v in (m.value for m in episode.messages(GRASP_ESTIMATE.name))
    ]


@dataclass(frozen=True)
class Truth:
    """The simulator's truth (``/sim/truth``): ``t_s`` (n,), ``gel_wrench_s`` (n, 6: the gel
    on the plug in S; fx, fy, fz N, tau_x, tau_y, tau_z N*m), and the chart's part."""

    t_s: np.ndarray
    gel_wrench_s: np.ndarray
    chart: ChartTruth


@_fields_checked("/sim/truth, /sim/tf")
def truth(episode: Episode) -> Truth | None:
    """The truth rows and the true hole (from ``/sim/tf``), None outside simulation."""
    rows = [m.value for m in episode.messages(SIM_TRUTH.name)]
    if not rows:
        return None

    def column(name: str, width: int) -> np.ndarray:
        return np.array([_vector(r[name], width) for r in rows], dtype=float).reshape(-1, width)

    hole = np.array([np.nan, np.nan])
    for message in episode.messages(SIM_TF.name):
        for transform in message.value.transforms:
            if transform.child_frame_id == HOLE_FRAME:
                hole = np.array([transform.translation.x, transform.translation.y])
    t = np.array([r["t_s"] for r in rows], dtype=float)
    chart = ChartTruth(
        t,
        column("wrist_wrench_t", 6),
        np.array([_number(r["contact_force_n"]) for r in rows]),
        np.array([_number(r.get("insertion_force_n")) for r in rows]),
        column("tip_xyz_b", 3),
        np.array([_number(r["depth_m"]) for r in rows]),
        hole,
    )
    return Truth(t, column("gel_wrench_s", 6), chart)


@_fields_checked("the drops (outcome, /episode/drops)")
def drops(episode: Episode) -> tuple[int, dict[str, int]]:
    """The records the writer dropped: the total and the count by topic, from the outcome,
    else (a file cut short) from the last ``/episode/drops`` message; (0, {}) if none."""
    outcome = episode.outcome
    if outcome is not None and "dropped_total" in outcome:
        by_topic = json.loads(outcome.get("dropped_by_topic") or "{}")
        return int(outcome["dropped_total"]), {k: int(v) for k, v in by_topic.items()}
    last = [m.value for m in episode.messages(DROPS.name)]
    if not last:
        return 0, {}
    return int(last[-1]["dropped_total"]), {k: int(v) for k, v in last[-1]["by_topic"].items()}
