"""How an episode's two rates become one LeRobot table (docs/EPISODES.md, "Export to
LeRobot: alignment").

LeRobot v3.0 has one ``fps`` per dataset: every row is one instant, and a video frame is
looked up at its row's timestamp. Our tactile camera runs at its own rate (25 Hz for the
GelSight Mini) and the control loop at 100 Hz. The export's rows are the **tactile frames**:

* ``fps`` is the camera's rate (the median interval between frames pushed, rounded to a
  whole number of frames per second, as LeRobot wants an integer);
* row ``k`` stands for time ``T_k = t_0 + k / fps`` on the loop's clock (``t_0``: when the
  first frame was pushed) and its ``timestamp`` is ``k / fps``. Its image is the newest frame
  pushed at or before ``T_k`` (``HOLD_TOLERANCE_S``): on a camera that drops a frame the
  previous one is shown again, and ``observation.tactile.frame_age_s`` says how old it is;
* ``observation.state`` is the robot as the control loop saw it at the tick at or before
  ``T_k`` (the tick that pushed the frame): TCP pose T2B (m, rad, xArm rpy) and gripper
  opening (m);
* ``observation.state.window`` keeps the higher rate: the same state at the last ``W``
  ticks up to that tick, oldest first, flattened row-major (``W = round(loop rate / fps)``,
  4 at 100 Hz / 25 Hz; the first rows repeat the first tick);
* ``observation.wrench``: the estimate the controller had for that frame (raw units, with
  ``valid`` 0 and the values 0 while the estimator was zeroing or had no reference);
* ``action`` is the command sent at that tick (TCP twist in B, m/s and rad/s, zero when none
  was sent; the gripper opening last commanded, m), and ``action.window`` the commands of
  the ``W`` ticks from that tick on, i.e. until the next frame: the action chunk that
  followed the frame.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from controller.episode import Episode
from controller.tactile.wrench import VALUE_FIELDS
from evaluation.episodes import episode_streams
from evaluation.episodes.episode_streams import LoggedFrame, Ticks
from evaluation.episodes.lerobot_dataset import DatasetEpisode, VectorFeature

HOLD_TOLERANCE_S = 1e-6
STATE_NAMES = ("tcp_x_m", "tcp_y_m", "tcp_z_m", "tcp_roll_rad", "tcp_pitch_rad",
               "tcp_yaw_rad", "gripper_width_m")  # fmt: skip
ACTION_NAMES = ("v_x_m_s", "v_y_m_s", "v_z_m_s", "w_x_rad_s", "w_y_rad_s", "w_z_rad_s",
                "gripper_target_m")  # fmt: skip
WRENCH_NAMES = (*VALUE_FIELDS, "contact", "valid")


class AlignmentError(ValueError):
    """An episode that cannot become dataset rows (one line)."""


@dataclass(frozen=True)
class AlignedEpisode:
    """An episode as dataset rows: the ``dataset`` episode, its ``fps``, the frames' size
    (``frame_hw``: height, width px), the ticks per row ``window``, how many rows
    ``repeated`` an older frame, and the control loop's rate (``loop_rate_hz``, Hz)."""

    dataset: DatasetEpisode
    fps: int
    frame_hw: tuple[int, int]
    window: int
    repeated: int
    loop_rate_hz: float = math.nan


def camera_fps(push_t_s: np.ndarray) -> int:
    """The camera's rate from the times frames were pushed (s): 1 / the median interval,
    rounded; AlignmentError with fewer than two frames."""
    if len(push_t_s) < 2:
        raise AlignmentError(f"{len(push_t_s)} tactile frame(s): need at least 2 to export")
    return max(1, round(1.0 / float(np.median(np.diff(push_t_s)))))


def frame_rows(push_t_s: np.ndarray, fps: int) -> tuple[np.ndarray, np.ndarray]:
    """The rows' times ``T_k = t_0 + k / fps`` (s, from the first push to the last) and,
    for each, the index of the newest frame pushed at or before it."""
    rows = math.floor((push_t_s[-1] - push_t_s[0]) * fps + 0.5) + 1
    row_t = push_t_s[0] + np.arange(rows) / fps
    source = np.searchsorted(push_t_s, row_t + HOLD_TOLERANCE_S, side="right") - 1
    return row_t, source


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
    push_t = np.array([frame.t_s for frame in logged])
    fps = camera_fps(push_t)
    row_t, source = frame_rows(push_t, fps)
    rows = len(row_t)
    tick = np.clip(np.searchsorted(ticks.t_s, row_t + HOLD_TOLERANCE_S, side="right") - 1, 0, None)
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
        VectorFeature("observation.wrench", WRENCH_NAMES, _wrench(episode, logged, source)),
        VectorFeature(
            "observation.tactile.frame_age_s", ("age_s",), (row_t - push_t[source])[:, None]
        ),
        VectorFeature("action", ACTION_NAMES, action[tick]),
        VectorFeature(
            "action.window",
            _window_names(ACTION_NAMES, window, forward=True),
            windows(action, tick, window, forward=True),
        ),
    )
    first = logged[0].image()
    frame_hw = (int(first.shape[0]), int(first.shape[1]))
    repeated = int(rows - len(np.unique(source)))
    dataset = DatasetEpisode(task, rows, _rgb_frames(logged, source), features)
    return AlignedEpisode(dataset, fps, frame_hw, window, repeated, loop_rate)


def _wrench(episode: Episode, logged: list[LoggedFrame], source: np.ndarray) -> np.ndarray:
    """The estimate of each row's frame (matched by push order), its flags last; zeros and
    ``valid`` 0 while the estimator zeroed or where nothing finite was logged."""
    found = episode_streams.estimates(episode)
    by_push = {int(p): i for i, p in enumerate(found.push_index)}
    table = np.zeros((len(logged), len(WRENCH_NAMES)))
    for push in range(len(logged)):
        i = by_push.get(push)
        if i is None or found.zeroing[i] or not np.isfinite(found.values[i]).all():
            continue
        table[push, : len(VALUE_FIELDS)] = found.values[i]
        table[push, -2:] = (float(found.contact[i]), 1.0)
    return table[source]


def _rgb_frames(logged: list[LoggedFrame], source: np.ndarray) -> Iterator[np.ndarray]:
    """Each row's image as RGB uint8 (H x W x 3), decoded once per frame."""
    last, image = -1, None
    for index in source:
        if index != last:
            decoded = logged[index].image()
            image = (
                np.repeat(decoded[:, :, None], 3, axis=2)
                if decoded.ndim == 2
                else decoded[:, :, ::-1]
            )
            last = index
        yield np.ascontiguousarray(image)
