"""An episode as a Rerun recording (``replay export EP --rerun OUT.rrd``; docs/EPISODES.md,
"Export to Rerun"), read through the episode reader (controller/episode/reader.py) and written
with ``rerun-sdk`` (the ``rerun`` extra), on one timeline, ``LOOP_TIMELINE``: the loop's
clock (s, a duration from the loop's start), so the recording lines up with the episode's
``t_s`` fields.

What goes where (entity paths are the episode's topics):

* every number of a JSON topic is a scalar series ``/TOPIC/FIELD`` (``rr.Scalars``; a list
  of k numbers one series of k components, a flag 0 or 1): the torques and forces
  (``/tactile/wrench``), the commands (``/control/command``), the arm's state
  (``/arm/status``), the loop's timing, the simulator's truth. A message that has no value
  for a field (an absent key) has no point there;
* every text field of a JSON topic is a ``rr.TextLog`` at ``/TOPIC/FIELD``, logged when it
  changes (the phase ``/loop/tick/phase``, who is in control ``/teleop/input/in_control_by``),
  and each transition one line at ``/machine/transition`` ("grasp -> approach:
  grasped_and_zeroed (rule)");
* ``/tactile/image``: each frame as logged (``rr.EncodedImage``, the JPEG or PNG bytes, not
  decoded again);
* ``/tactile/field``: each displacement field as ``rr.Arrows2D`` (origins at the grid's
  cells, vectors ``(u_mm, v_mm)``, both in mm in the sensor frame S);
* ``/tf``, ``/tf_static``, ``/sim/tf``: each transform as ``rr.Transform3D`` at
  ``/frames/ROOT/.../CHILD`` (the frame tree, built from every parent-child pair of the
  episode).
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from controller.episode import Episode, grid_arrays
from controller.episode.topics import TACTILE_FIELD, TACTILE_IMAGE, TOPICS, TRANSITION

LOOP_TIMELINE = "loop_time"
APPLICATION_ID = "tactile_insertion_replay"
FRAMES_ROOT = "/frames"
TRANSFORM_SCHEMA = "foxglove.FrameTransforms"
MEDIA_TYPES = {"jpeg": "image/jpeg", "png": "image/png"}


class RerunMissing(ImportError):
    """``rerun-sdk`` is not installed (the ``rerun`` extra)."""


def rerun_sdk() -> Any:
    """The ``rerun`` module; RerunMissing if ``rerun-sdk`` is not installed."""
    try:
        import rerun
    except ImportError as error:
        raise RerunMissing(str(error)) from None
    return rerun


def write_recording(episode: Episode, path: Path) -> dict[str, int]:
    """Write ``episode`` as a Rerun recording to ``path`` (the caller makes it atomic);
    returns how many rows went to each kind (scalars, texts, images, fields, transforms).
    RerunMissing without ``rerun-sdk``."""
    rr = rerun_sdk()
    recording = rr.RecordingStream(APPLICATION_ID)
    recording.save(str(path))
    counts = {"scalars": 0, "texts": 0, "images": 0, "fields": 0, "transforms": 0}
    json_topics = [
        t
        for t in episode.topics
        if t in TOPICS and TOPICS[t].encoding == "json" and t != TRANSITION.name
    ]
    for topic in json_topics:
        scalars, texts = _json_series(episode.messages(topic))
        for field, (times, values) in scalars.items():
            recording.send_columns(
                f"{topic}/{field}",
                indexes=[rr.TimeColumn(LOOP_TIMELINE, duration=np.asarray(times))],
                columns=rr.Scalars.columns(scalars=np.asarray(values, dtype=np.float64)),
            )
            counts["scalars"] += len(times)
        for field, lines in texts.items():
            for t_s, text in lines:
                recording.set_time(LOOP_TIMELINE, duration=t_s)
                recording.log(f"{topic}/{field}", rr.TextLog(text))
            counts["texts"] += len(lines)
    for message in episode.messages(TRANSITION.name):
        v = message.value
        rule = f" ({v['rule']})" if v.get("rule") else ""
        recording.set_time(LOOP_TIMELINE, duration=message.t_s)
        recording.log(TRANSITION.name, rr.TextLog(f"{v['from']} -> {v['to']}: {v['reason']}{rule}"))
        counts["texts"] += 1
    for message in episode.messages(TACTILE_IMAGE.name):
        recording.set_time(LOOP_TIMELINE, duration=message.t_s)
        media = MEDIA_TYPES.get(message.value.format, f"image/{message.value.format}")
        image = rr.EncodedImage(contents=bytes(message.value.data), media_type=media)
        recording.log(TACTILE_IMAGE.name, image)
        counts["images"] += 1
    for message in episode.messages(TACTILE_FIELD.name):
        origins, vectors = field_arrows(message.value)
        recording.set_time(LOOP_TIMELINE, duration=message.t_s)
        recording.log(TACTILE_FIELD.name, rr.Arrows2D(origins=origins, vectors=vectors))
        counts["fields"] += 1
    counts["transforms"] = _log_transforms(rr, recording, episode)
    recording.flush()
    recording.disconnect()
    return counts


def _json_series(
    messages: Iterable[Any],
) -> tuple[dict[str, tuple[list[float], list[Any]]], dict[str, list[tuple[float, str]]]]:
    """The numeric fields of a JSON topic's messages as series (field -> times, values; a
    vector field keeps the width of its first value, other widths are skipped) and its text
    fields as the changes (field -> (time, text))."""
    scalars: dict[str, tuple[list[float], list[Any]]] = {}
    widths: dict[str, int] = {}
    texts: dict[str, list[tuple[float, str]]] = defaultdict(list)
    last_text: dict[str, str] = {}
    for message in messages:
        for field, value in message.value.items():
            number = _numbers(value)
            if number is not None:
                width = widths.setdefault(field, len(number))
                if len(number) == width:
                    times, values = scalars.setdefault(field, ([], []))
                    times.append(message.t_s)
                    values.append(number)
            elif isinstance(value, str) and last_text.get(field) != value:
                last_text[field] = value
                texts[field].append((message.t_s, value))
    return scalars, dict(texts)


def _numbers(value: object) -> list[float] | None:
    """``value`` as a list of numbers (a flag 0 or 1), None if it is not numeric or empty."""
    if isinstance(value, bool | int | float):
        return [float(value)]
    if (
        isinstance(value, list)
        and value
        and all(isinstance(v, int | float) and not isinstance(v, bool) for v in value)
    ):
        return [float(v) for v in value]
    return None


def field_arrows(grid: Any) -> tuple[np.ndarray, np.ndarray]:
    """A ``/tactile/field`` grid as arrows: each cell's centre (mm, in S: the grid's corner
    plus half a cell) and its displacement ``(u_mm, v_mm)``, each (cells, 2)."""
    arrays = grid_arrays(grid)
    rows, cols = arrays["u_mm"].shape
    dx_mm, dy_mm = grid.cell_size.x * 1e3, grid.cell_size.y * 1e3
    x0_mm, y0_mm = grid.pose.position.x * 1e3, grid.pose.position.y * 1e3
    x = x0_mm + (np.arange(cols) + 0.5) * dx_mm
    y = y0_mm + (np.arange(rows) + 0.5) * dy_mm
    gx, gy = np.meshgrid(x, y)
    origins = np.column_stack([gx.ravel(), gy.ravel()])
    vectors = np.column_stack([arrays["u_mm"].ravel(), arrays["v_mm"].ravel()])
    return origins, vectors


def frame_paths(pairs: Iterable[tuple[str, str]]) -> Mapping[str, str]:
    """Each child frame's entity path under ``FRAMES_ROOT``: its parents' chain from the
    root (a frame with no parent), e.g. ``/frames/B/T/S``."""
    parent = dict((child, p) for p, child in pairs)
    paths: dict[str, str] = {}

    def path(frame: str, seen: tuple[str, ...] = ()) -> str:
        if frame in paths:
            return paths[frame]
        up = parent.get(frame)
        if up is None or up in seen:  # a root, or a cycle cut where it closes
            found = f"{FRAMES_ROOT}/{frame}"
        else:
            found = f"{path(up, (*seen, frame))}/{frame}"
        paths[frame] = found
        return found

    for child in parent:
        path(child)
    return paths


def _transforms(episode: Episode) -> list[tuple[float, Any]]:
    topics = [t for t in episode.topics if t in TOPICS and TOPICS[t].schema == TRANSFORM_SCHEMA]
    return [
        (message.t_s, transform)
        for message in episode.messages(*topics)
        for transform in message.value.transforms
    ] if topics else []  # fmt: skip


def _log_transforms(rr: Any, recording: Any, episode: Episode) -> int:
    found = _transforms(episode)
    paths = frame_paths((tf.parent_frame_id, tf.child_frame_id) for _, tf in found)
    for t_s, tf in found:
        p, q = tf.translation, tf.rotation
        recording.set_time(LOOP_TIMELINE, duration=t_s)
        recording.log(
            paths[tf.child_frame_id],
            rr.Transform3D(
                translation=[p.x, p.y, p.z], quaternion=rr.Quaternion(xyzw=[q.x, q.y, q.z, q.w])
            ),
        )
    return len(found)
