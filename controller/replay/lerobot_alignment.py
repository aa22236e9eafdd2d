"""How an episode's two rates become one LeRobot table (docs/EPISODES.md, "Export to
LeRobot: alignment").

LeRobot v3.0 has one ``fps`` per dataset: every row is one instant, and a video frame is
looked up at its row's timestamp. Our tactile camera runs at its own rate (25 Hz for the
GelSight Mini) and the control loop at 100 Hz. The export's rows are the **tactile frames**,
one row per frame captured and pushed, none repeated and none left out:

* ``fps`` is the camera's rate (the median interval between frames captured, rounded to a
  whole number of frames per second, as LeRobot wants an integer);
* row ``k`` is frame ``k``; its ``timestamp`` is the nominal ``k / fps`` (the frame's
  presentation time in the video, where LeRobot looks it up within its ``tolerance_s``), and
  ``observation.tactile.capture_time_s`` its real capture time, s after the episode's first
  frame's (on the loop's clock; a camera's jitter and drops show there);
* ``observation.state`` is the robot as the control loop saw it at the tick at or before
  the frame's push (``TICK_TOLERANCE_S``; the tick that pushed the frame): TCP pose T2B (m,
  rad, xArm rpy) and gripper opening (m);
* ``observation.state.window`` keeps the higher rate: the same state at the last ``W``
  ticks up to that tick, oldest first, flattened row-major (``W = round(loop rate / fps)``,
  4 at 100 Hz / 25 Hz; the first rows repeat the first tick);
* ``observation.wrench``: the estimate the controller had for that frame (raw units, with
  ``valid`` 0 and the values 0 while the estimator was zeroing or had no reference);
* ``action`` is the command sent at that tick (TCP twist in B, m/s and rad/s, zero when none
  was sent; the gripper opening last commanded, m), and ``action.window`` the commands of
  the ``W`` ticks from that tick on, i.e. about until the next frame: the action chunk
  that followed the frame.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from controller.episode import Episode
from controller.replay import episode_streams
from controller.replay.episode_streams import LoggedFrame, Ticks
from controller.replay.lerobot_dataset import DatasetEpisode, VectorFeature
from controller.tactile.wrench import VALUE_FIELDS

TICK_TOLERANCE_S = 1e-6
"""A tick this much after a frame's push time (s) still counts as at it (float rounding)."""
STATE_NAMES = ("tcp_x_m", "tcp_y_m", "tcp_z_m", "tcp_roll_rad", "tcp_pitch_rad",
               "tcp_yaw_rad", "gripper_width_m")  # fmt: skip
ACTION_NAMES = ("v_x_m_s", "v_y_m_s", "v_z_m_s", "w_x_rad_s", "w_y_rad_s", "w_z_rad_s",
                "gripper_target_m")  # fmt: skip
WRENCH_NAMES = (*VALUE_FIELDS, "contact", "valid")
CAPTURE_KEY = "observation.tactile.capture_time_s"


class AlignmentError(ValueError):
    """An episode that cannot become dataset rows (one line)."""


@dataclass(frozen=True)
class AlignedEpisode:
    """An episode as dataset rows: the ``dataset`` episode, its ``fps``, the frames' size
    (``frame_hw``: height, width px), the ticks per row ``window``, the largest distance
    between a frame's capture time and its nominal timestamp (``drift_s``, s), and the
    control loop's rate (``loop_rate_hz``, Hz)."""

    dataset: DatasetEpisode
    fps: int
    frame_hw: tuple[int, int]
    window: int
    drift_s: float
    loop_rate_hz: float = math.nan


def camera_fps(capture_t_s: np.ndarray) -> int:
    """The camera's rate from the frames' capture times (s): 1 / the median interval,
    rounded; AlignmentError with fewer than two frames."""
    if len(capture_t_s) < 2:
        raise AlignmentError(f"{len(capture_t_s)} tactile frame(s): need at least 2 to export")
    return max(1, round(1.0 / float(np.median(np.diff(capture_t_s)))))


def frame_times(capture_t_s: np.ndarray, fps: int) -> tuple[np.ndarray, np.ndarray]:
    """Each frame's row times: the nominal ``timestamp`` ``k / fps`` and the capture time
    after the first frame's (both s)."""
    nominal = np.arange(len(capture_t_s)) / fps
    return nominal, capture_t_s - capture_t_s[0]


def _state(ticks: Ticks) -> np.ndarray:
    return np.column_stack([ticks.tcp_xyz_m, ticks.tcp_rpy_rad, ticks.gripper_width_m])


def _action(ticks: Ticks) -> np.ndarray:
    twist = np.nan_to_num(ticks.twist, nan=0.0)
    target = ticks.gripper_target_m
    held = np.where(np.isnan(target), ticks.gripper_width_m, target)
    return np.column_stack([twist, held])


def windows(values: np.ndarray, ends: np.ndarray, width: int, forward: bool) -> np.ndarray:
    """For each row index in ``ends``: ``width`` rows of ``values`` ending there (or
    starting there, ``forward``), clipped to the table, flattened."""
    steps = np.arange(width) if forward else np.arange(-width + 1, 1)
    rows = np.clip(ends[:, None] + steps[None, :], 0, len(values) - 1)
    return values[rows].reshape(len(ends), -1)


def _window_names(names: tuple[str, ...], width: int, forward: bool) -> tuple[str, ...]:
    offsets = range(width) if forward else range(-width + 1, 1)
    return tuple(f"t{offset:+d}/{name}" for offset in offsets for name in names)


def align(episode: Episode, task: str) -> AlignedEpisode:
    """The dataset rows of ``episode`` (see the module doc), for the LeRobot ``task``
    sentence. AlignmentError if the episode has too few frames or no ticks."""
    logged = list(episode_streams.frames(episode))
    ticks = episode_streams.ticks(episode)
    if len(ticks) == 0:
        raise AlignmentError("no control ticks (/loop/tick) to take the robot's state from")
    capture = np.array([frame.capture_t_s for frame in logged])
    push_t = np.array([frame.t_s for frame in logged])
    fps = camera_fps(capture)
    nominal, captured = frame_times(capture, fps)
    tick = np.clip(np.searchsorted(ticks.t_s, push_t + TICK_TOLERANCE_S, side="right") - 1, 0, None)
    loop_rate = 1.0 / float(np.median(np.diff(ticks.t_s))) if len(ticks) > 1 else fps
    window = max(1, round(loop_rate / fps))
    state, action = _state(ticks), _action(ticks)
    features = (
        VectorFeature("observation.state", STATE_NAMES, state[tick]),
        VectorFeature(
            "observation.state.window",
            _window_names(STATE_NAMES, window, forward=False),
            windows(state, tick, window, forward=False),
        ),
        VectorFeature("observation.wrench", WRENCH_NAMES, _wrench(episode, len(logged))),
        VectorFeature(CAPTURE_KEY, ("capture_time_s",), captured[:, None]),
        VectorFeature("action", ACTION_NAMES, action[tick]),
        VectorFeature(
            "action.window",
            _window_names(ACTION_NAMES, window, forward=True),
            windows(action, tick, window, forward=True),
        ),
    )
    first = logged[0].image()
    frame_hw = (int(first.shape[0]), int(first.shape[1]))
    drift = float(np.max(np.abs(captured - nominal)))
    dataset = DatasetEpisode(task, len(logged), _rgb_frames(logged), features)
    return AlignedEpisode(dataset, fps, frame_hw, window, drift, loop_rate)


def _wrench(episode: Episode, frames: int) -> np.ndarray:
    """The estimate of each frame (matched by push order), its flags last; zeros and
    ``valid`` 0 while the estimator zeroed or where nothing finite was logged."""
    found = episode_streams.estimates(episode)
    by_push = {int(p): i for i, p in enumerate(found.push_index)}
    table = np.zeros((frames, len(WRENCH_NAMES)))
    for push in range(frames):
        i = by_push.get(push)
        if i is None or found.zeroing[i] or not np.isfinite(found.values[i]).all():
            continue
        table[push, : len(VALUE_FIELDS)] = found.values[i]
        table[push, -2:] = (float(found.contact[i]), 1.0)
    return table


def _rgb_frames(logged: list[LoggedFrame]) -> Iterator[np.ndarray]:
    """Each frame's image as RGB uint8 (H x W x 3), decoded when asked."""
    for frame in logged:
        decoded = frame.image()
        image = (
            np.repeat(decoded[:, :, None], 3, axis=2) if decoded.ndim == 2 else decoded[:, :, ::-1]
        )
        yield np.ascontiguousarray(image)
