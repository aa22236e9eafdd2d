"""A LeRobot v3.0 dataset written from episodes held as plain arrays: pyarrow for the
parquet files, PyAV for the video, no ``lerobot`` package (it pulls in torch and needs
Python 3.12).

The layout (LeRobot v3.0, ``CODEBASE_VERSION = "v3.0"``; docs/EPISODES.md, "Export to
LeRobot")::

    DIR/meta/info.json                       codebase_version, fps, features, path templates,
                                             totals, splits
    DIR/meta/stats.json                      per feature: min, max, mean, std, count, q01..q99
    DIR/meta/tasks.parquet                   task string (the index) -> task_index
    DIR/meta/episodes/chunk-000/file-000.parquet   one row per episode: its tasks, length,
                                             where its rows and video frames are, its stats
    DIR/data/chunk-000/file-000.parquet      one row per frame: the numeric features,
                                             timestamp, frame_index, episode_index, index,
                                             task_index
    DIR/videos/observation.images.tactile/chunk-000/file-000.mp4   every episode's frames,
                                             one after the other

Every episode goes into chunk 0, file 0 (one export is far below LeRobot's 100 MB data and
200 MB video file sizes). Statistics are taken per episode and aggregated over the dataset
as LeRobot does (controller/replay/lerobot_stats.py): the numeric features over every row,
the video over the frames LeRobot samples, per RGB channel, scaled to [0, 1], shape (3, 1, 1).

Memory: the episodes are taken one at a time from any iterable (a generator that reads
each episode file when asked): each one's frames go to the video encoder as they come and
its sampled frames into per-channel histograms (controller/replay/image_stats.py), so
only the numeric rows of the episodes already written stay in memory.

The dataset is built in a hidden folder beside DIR and renamed to DIR only when complete
(``controller.cli.outputs``): an error or an interruption leaves no DIR.
"""

from __future__ import annotations

import json
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from controller.cli.outputs import discard_folder, partial_folder, publish_folder
from controller.replay.image_stats import ImageStats
from controller.replay.lerobot_stats import (
    Stats,
    aggregate_features,
    downsampled,
    numeric_stats,
    sample_indices,
)
from controller.replay.lerobot_video import open_video, video_info

CODEBASE_VERSION = "v3.0"
CHUNKS_SIZE = 1000
DATA_FILES_SIZE_IN_MB = 100
VIDEO_FILES_SIZE_IN_MB = 200
CHUNK_FILE = "chunk-{chunk_index:03d}/file-{file_index:03d}"
DATA_PATH = "data/" + CHUNK_FILE + ".parquet"
VIDEO_PATH = "videos/{video_key}/" + CHUNK_FILE + ".mp4"
EPISODES_PATH = "meta/episodes/" + CHUNK_FILE + ".parquet"
TASKS_PATH = "meta/tasks.parquet"
IMAGE_KEY = "observation.images.tactile"
INDEX_FEATURES = {
    "timestamp": "float32",
    "frame_index": "int64",
    "episode_index": "int64",
    "index": "int64",
    "task_index": "int64",
}
"""The columns every LeRobot v3.0 data file has, with their dtypes."""


@dataclass(frozen=True)
class VectorFeature:
    """A numeric feature: ``key`` (e.g. ``observation.state``), the ``names`` of its
    components (units in the names), and ``values``, one row per dataset frame, float32."""

    key: str
    names: tuple[str, ...]
    values: np.ndarray

    def __post_init__(self) -> None:
        values = np.asarray(self.values, dtype=np.float32)
        if values.ndim != 2 or values.shape[1] != len(self.names):
            raise ValueError(
                f"feature {self.key!r}: expected values of shape (frames, {len(self.names)}), "
                f"got {values.shape}"
            )
        object.__setattr__(self, "values", values)


@dataclass(frozen=True)
class DatasetEpisode:
    """One episode as the dataset stores it: its ``task`` (a sentence), its tactile
    ``frames`` (RGB uint8, H x W x 3, one per dataset frame, read once, in order: a
    generator is fine) and its numeric ``features`` (each with one row per frame)."""

    task: str
    length: int
    frames: Iterable[np.ndarray]
    features: tuple[VectorFeature, ...]

    def __post_init__(self) -> None:
        if self.length < 1:
            raise ValueError("an episode needs at least one frame")
        for feature in self.features:
            if len(feature.values) != self.length:
                raise ValueError(
                    f"feature {feature.key!r}: {len(feature.values)} rows for {self.length} frames"
                )


@dataclass(frozen=True)
class WrittenDataset:
    """What ``write_dataset`` wrote: its folder, episodes, frames and fps."""

    root: Path
    episodes: int
    frames: int
    fps: int


def write_dataset(
    episodes: Iterable[DatasetEpisode],
    root: Path,
    fps: int,
    frame_hw: tuple[int, int],
    robot_type: str | None = None,
) -> WrittenDataset:
    """Write ``episodes`` (frames of ``frame_hw`` = (height, width) px, at ``fps`` frames
    per second, sharing their features' keys and names; taken one at a time, see the module
    doc) as a LeRobot v3.0 dataset at ``root``, which must not exist. ValueError (naming the
    episode) on a mismatch; what the iterable raises propagates. Either way no ``root``
    and no partial folder is left."""
    partial = partial_folder(root)
    try:
        written = _write(iter(episodes), partial, fps, frame_hw, robot_type)
        publish_folder(partial, root, replace=False)
    except BaseException:
        discard_folder(partial)
        raise
    return WrittenDataset(root, written.episodes, written.frames, fps)


def _location(template: str, **keys: Any) -> str:
    return template.format(chunk_index=0, file_index=0, **keys)


@dataclass
class _Written:
    """What is kept of each episode written: its task, length, numeric rows and statistics
    (never its frames)."""

    layout: list[tuple[str, tuple[str, ...]]]
    features: tuple[VectorFeature, ...]
    tasks: list[str]
    lengths: list[int]
    tables: list[pa.Table]
    stats: list[dict[str, Stats]]

    @property
    def episodes(self) -> int:
        return len(self.lengths)

    @property
    def frames(self) -> int:
        return sum(self.lengths)


def _write(
    episodes: Iterable[DatasetEpisode],
    root: Path,
    fps: int,
    frame_hw: tuple[int, int],
    robot_type: str | None,
) -> _Written:
    height, width = frame_hw
    video_path = root / _location(VIDEO_PATH, video_key=IMAGE_KEY)
    video_path.parent.mkdir(parents=True)
    written: _Written | None = None
    task_order: dict[str, int] = {}
    with open_video(video_path, fps, width, height) as video:
        for number, episode in enumerate(episodes):
            layout = [(f.key, f.names) for f in episode.features]
            if written is None:
                written = _Written(layout, episode.features, [], [], [], [])
            elif layout != written.layout:
                raise ValueError(f"episode {number}: its features differ from episode 0's")
            task_index = task_order.setdefault(episode.task, len(task_order))
            images = _encode_frames(episode, number, video)
            table = _data_table(episode, number, written.frames, task_index, fps)
            written.tables.append(table)
            written.stats.append(_episode_stats(table, written.features, images))
            written.tasks.append(episode.task)
            written.lengths.append(episode.length)
            del episode  # its frames (and the episode file behind them) may go now
    if written is None:
        raise ValueError("no episodes to write")
    data_path = root / _location(DATA_PATH)
    data_path.parent.mkdir(parents=True)
    table = pa.concat_tables(written.tables)
    pq.write_table(table, data_path, compression="snappy")
    features = _features_info(written.features, frame_hw, video_info(video_path))
    _write_episodes(root, written, fps)
    tasks = list(task_order)
    pd.DataFrame({"task_index": range(len(tasks))}, index=tasks).to_parquet(root / TASKS_PATH)
    _write_json(root / "meta" / "stats.json", _plain(aggregate_features(written.stats)))
    info = {
        "codebase_version": CODEBASE_VERSION,
        "robot_type": robot_type,
        "total_episodes": written.episodes,
        "total_frames": int(table.num_rows),
        "total_tasks": len(tasks),
        "chunks_size": CHUNKS_SIZE,
        "data_files_size_in_mb": DATA_FILES_SIZE_IN_MB,
        "video_files_size_in_mb": VIDEO_FILES_SIZE_IN_MB,
        "fps": fps,
        "splits": {"train": f"0:{written.episodes}"},
        "data_path": DATA_PATH,
        "video_path": VIDEO_PATH,
        "features": features,
    }
    _write_json(root / "meta" / "info.json", info)
    return written


def _encode_frames(episode: DatasetEpisode, number: int, video: Any) -> ImageStats:
    """Encode the episode's frames; the statistics of those LeRobot samples."""
    keep = set(sample_indices(episode.length).tolist())
    sampled = ImageStats()
    count = 0
    for frame in episode.frames:
        if count >= episode.length:
            break
        try:
            video.write(frame)
        except ValueError as exc:
            raise ValueError(f"episode {number}, frame {count}: {exc}") from None
        if count in keep:
            sampled.add(downsampled(np.asarray(frame, dtype=np.uint8)))
        count += 1
    if count != episode.length:
        raise ValueError(f"episode {number}: {count} frames for a length of {episode.length}")
    return sampled


def _data_table(
    episode: DatasetEpisode, number: int, first: int, task_index: int, fps: int
) -> pa.Table:
    n = episode.length
    columns: dict[str, pa.Array] = {}
    for feature in episode.features:
        columns[feature.key] = _column(feature.values)
    frame_index = np.arange(n, dtype=np.int64)
    columns["timestamp"] = pa.array((frame_index / fps).astype(np.float32))
    columns["frame_index"] = pa.array(frame_index)
    columns["episode_index"] = pa.array(np.full(n, number, dtype=np.int64))
    columns["index"] = pa.array(first + frame_index)
    columns["task_index"] = pa.array(np.full(n, task_index, dtype=np.int64))
    return pa.table(columns)


def _column(values: np.ndarray) -> pa.Array:
    """A float32 column: a scalar for one component, else a fixed-size list (LeRobot's
    ``Sequence(length=k)``)."""
    if values.shape[1] == 1:
        return pa.array(values[:, 0])
    return pa.FixedSizeListArray.from_arrays(pa.array(values.reshape(-1)), values.shape[1])


def _features_info(
    vectors: tuple[VectorFeature, ...], frame_hw: tuple[int, int], video: dict[str, object]
) -> dict[str, dict[str, Any]]:
    features: dict[str, dict[str, Any]] = {
        IMAGE_KEY: {
            "dtype": "video",
            "shape": [*frame_hw, 3],
            "names": ["height", "width", "channels"],
            "info": video,
        }
    }
    for feature in vectors:
        features[feature.key] = {
            "dtype": "float32",
            "shape": [len(feature.names)],
            "names": list(feature.names),
        }
    for key, dtype in INDEX_FEATURES.items():
        features[key] = {"dtype": dtype, "shape": [1], "names": None}
    return features


def _table_values(table: pa.Table, key: str) -> np.ndarray:
    """The column ``key`` as an (n, k) array."""
    column = table.column(key).combine_chunks()
    if pa.types.is_fixed_size_list(column.type):
        return column.flatten().to_numpy().reshape(len(column), column.type.list_size)
    return column.to_numpy().reshape(-1, 1)


def _episode_stats(
    table: pa.Table, vectors: tuple[VectorFeature, ...], images: ImageStats
) -> dict[str, Stats]:
    """One episode's statistics (its rows in ``table``), feature by feature."""
    keys = [f.key for f in vectors] + list(INDEX_FEATURES)
    stats = {key: numeric_stats(_table_values(table, key)) for key in keys}
    stats[IMAGE_KEY] = images.stats()
    return stats


def _plain(stats: dict[str, Stats]) -> dict[str, dict[str, Any]]:
    return {key: {k: v.tolist() for k, v in values.items()} for key, values in stats.items()}


def _write_episodes(root: Path, written: _Written, fps: int) -> None:
    rows: list[dict[str, Any]] = []
    first = 0
    for number, (task, length, stats) in enumerate(
        zip(written.tasks, written.lengths, written.stats, strict=True)
    ):
        video = f"videos/{IMAGE_KEY}/"
        row: dict[str, Any] = {
            "episode_index": number,
            "tasks": [task],
            "length": length,
            "data/chunk_index": 0,
            "data/file_index": 0,
            "dataset_from_index": first,
            "dataset_to_index": first + length,
            video + "chunk_index": 0,
            video + "file_index": 0,
            video + "from_timestamp": first / fps,
            video + "to_timestamp": (first + length) / fps,
            "meta/episodes/chunk_index": 0,
            "meta/episodes/file_index": 0,
        }
        for key, values in _plain(stats).items():
            for name, value in values.items():
                row[f"stats/{key}/{name}"] = value
        rows.append(row)
        first += length
    path = root / _location(EPISODES_PATH)
    path.parent.mkdir(parents=True)
    pq.write_table(pa.Table.from_pylist(rows), path)


def _write_json(path: Path, value: object) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(value, indent=4) + "\n")
