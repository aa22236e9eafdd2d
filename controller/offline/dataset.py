"""Calibration datasets: tactile video plus force/torque readings, recorded or simulated.

A dataset is a folder::

    meta.yaml      format, sensor profile, load factor, reference and open intervals, segments
    tactile.avi    the tactile frames, Motion-JPEG (quality 95; cameras stream MJPEG too)
    tactile.csv    frame,t_s                          -- one row per frame, capture time
    ft.csv         t_s,fx_n,fy_n,fz_n,tau_x_nm,tau_y_nm,tau_z_nm
                                                      -- the force/torque sensor, in frame S
    truth.csv      (simulated datasets only) the simulator's own state per frame, for
                   diagnostics; calibration never reads it

Both CSVs share one clock (seconds). ``meta.yaml`` holds:

* ``format``: ``tactile-insertion/dataset/v1``; ``sensor``: a sensor profile name
  (configs/sensors); ``source``: ``simulation`` or ``recording``;
* ``gel_load_factor``: the live gel's wrench on the object = this factor times the F/T
  reading (-0.5 for a plate between two identical gels, the jig's geometry);
* ``reference``: ``[t_start_s, t_end_s]``, gripped and still (the zeroing frames);
  ``open``: the same for frames before the grasp (no contact), or null;
* ``segments``: the experiments, each ``{axis: x|y|z, amplitude_nm, t_start_s, t_end_s}``;
* ``extras``: anything else (the simulator's settings and seed, the object...).

Writing is all or nothing: ``DatasetWriter`` builds the dataset in a hidden folder beside
the destination (``.NAME.XXXXXXXX.partial``) and renames it into place on ``close()``, after
``meta.yaml``; an error or an interruption inside its ``with`` block removes the partial
folder, and a killed process leaves only that hidden folder, without ``meta.yaml``.

Reading is strict: ``Dataset`` loads ``meta.yaml`` through the configuration loader
(``core.config``) and refuses a folder whose files disagree with each other or with the
meta: frame numbers not 0..n-1, times not finite and increasing, a video whose frame count
differs from ``tactile.csv``, intervals or segments outside the recorded frames and F/T
readings, a segment without frames. Errors are ConfigErrors naming the file.
"""

from __future__ import annotations

import csv
import math
import warnings
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import cv2
import numpy as np
import yaml

from controller.cli.outputs import discard_folder, partial_folder, publish_folder
from controller.offline.video import ReadLog, VideoError, VideoFile
from core.config import Config, ConfigError, build, config_dataclass, load_yaml, number

FORMAT = "tactile-insertion/dataset/v1"
VIDEO, FRAMES_CSV, FT_CSV, TRUTH_CSV, META = (
    "tactile.avi",
    "tactile.csv",
    "ft.csv",
    "truth.csv",
    "meta.yaml",
)
FT_COLUMNS = ("t_s", "fx_n", "fy_n", "fz_n", "tau_x_nm", "tau_y_nm", "tau_z_nm")
JPEG_QUALITY = 95
_TIME_LIMIT_S = 1e12  # times are finite numbers of seconds on the recording's clock
_SLACK_INTERVALS = 2.0  # a segment may end this many frame (or F/T) intervals after the last


@config_dataclass
class Segment(Config):
    """One experiment: torques about S's ``axis`` up to ``amplitude_nm`` during
    [t_start_s, t_end_s)."""

    axis: Literal["x", "y", "z"]
    amplitude_nm: float = number(-1e3, 1e3)
    t_start_s: float = number(-_TIME_LIMIT_S, _TIME_LIMIT_S)
    t_end_s: float = number(-_TIME_LIMIT_S, _TIME_LIMIT_S)

    def __post_init__(self) -> None:
        if not self.t_start_s < self.t_end_s:
            raise ValueError(
                f"key 't_end_s': expected a time after t_start_s ({self.t_start_s}), "
                f"got {self.t_end_s}"
            )


@config_dataclass
class _MetaHead(Config):
    """The scalar keys of meta.yaml, loaded through the configuration loader."""

    format: Literal["tactile-insertion/dataset/v1"]
    sensor: str
    source: Literal["simulation", "recording"]
    gel_load_factor: float = number(-1.0, 1.0)

    def __post_init__(self) -> None:
        if self.gel_load_factor == 0:
            raise ValueError("key 'gel_load_factor': expected a non-zero number in [-1, 1], got 0")


_STRUCTURED_KEYS = ("reference", "open", "segments", "extras")


@dataclass(frozen=True)
class DatasetMeta:
    sensor: str
    source: str
    gel_load_factor: float
    reference: tuple[float, float]
    open: tuple[float, float] | None
    segments: tuple[Segment, ...]
    extras: Mapping[str, Any]


class DatasetWriter:
    """Writes a dataset folder; frames and F/T rows go to disk as they come, into a hidden
    partial folder. ``close()`` (or leaving the ``with`` block normally) writes
    ``meta.yaml`` and renames the folder into place; ``abort()`` (or leaving the block on an
    exception or interruption) removes it. ``replace``: an existing dataset at ``folder``
    is replaced once the new one is complete (without it, an existing ``folder`` is an
    error)."""

    def __init__(
        self, folder: Path | str, meta: DatasetMeta, frame_rate_hz: float, replace: bool = False
    ) -> None:
        self.folder = Path(folder)
        if self.folder.exists() and not replace:
            raise FileExistsError(17, "already exists; not replaced", str(self.folder))
        self.meta = meta
        self._replace = replace
        self._rate = frame_rate_hz
        self._partial = partial_folder(self.folder)
        self._video: cv2.VideoWriter | None = None
        self._frames = open(self._partial / FRAMES_CSV, "w", newline="")
        self._frames_csv = csv.writer(self._frames)
        self._frames_csv.writerow(("frame", "t_s"))
        self._count = 0
        self._truth: Any = None
        self._truth_csv: Any = None
        self._finished = False

    def __enter__(self) -> DatasetWriter:
        return self

    def __exit__(self, exc_type: object, *exc: object) -> None:
        if exc_type is None:
            self.close()
        else:
            self.abort()

    def add_frame(self, t_s: float, image: np.ndarray) -> None:
        """Append a BGR uint8 frame captured at ``t_s``."""
        if self._video is None:
            height, width = image.shape[:2]
            self._video = cv2.VideoWriter(
                str(self._partial / VIDEO),
                cv2.CAP_OPENCV_MJPEG,
                cv2.VideoWriter.fourcc(*"MJPG"),
                self._rate,
                (width, height),
            )
            self._video.set(cv2.VIDEOWRITER_PROP_QUALITY, JPEG_QUALITY)
        self._video.write(np.ascontiguousarray(image))
        self._frames_csv.writerow((self._count, repr(float(t_s))))
        self._count += 1

    def write_ft(self, t_s: np.ndarray, wrench: np.ndarray) -> None:
        """All F/T readings at once: times (n,) s and wrenches (n, 6) N, N*m in S."""
        table = np.column_stack([t_s, wrench])
        np.savetxt(
            self._partial / FT_CSV,
            table,
            delimiter=",",
            header=",".join(FT_COLUMNS),
            comments="",
            fmt="%.9g",
        )

    def add_truth(self, row: Mapping[str, float]) -> None:
        """Append the simulator's state for the latest frame (simulated datasets only)."""
        if self._truth is None:
            self._truth = open(self._partial / TRUTH_CSV, "w", newline="")
            self._truth_csv = csv.DictWriter(self._truth, fieldnames=list(row))
            self._truth_csv.writeheader()
        self._truth_csv.writerow({k: repr(float(v)) for k, v in row.items()})

    def _release(self) -> None:
        if self._video is not None:
            self._video.release()
            self._video = None
        for handle in (self._frames, self._truth):
            if handle is not None and not handle.closed:
                handle.close()

    def close(self) -> None:
        """Finish the files, write ``meta.yaml`` last and move the dataset into place."""
        if self._finished:
            return
        self._finished = True
        try:
            self._release()
            meta = self.meta
            document = {
                "format": FORMAT,
                "sensor": meta.sensor,
                "source": meta.source,
                "gel_load_factor": meta.gel_load_factor,
                "reference": list(meta.reference),
                "open": None if meta.open is None else list(meta.open),
                "segments": [vars(s) for s in meta.segments],
                "extras": dict(meta.extras),
            }
            (self._partial / META).write_text(yaml.safe_dump(document, sort_keys=False))
            publish_folder(self._partial, self.folder, self._replace)
        except BaseException:
            discard_folder(self._partial)
            raise

    def abort(self) -> None:
        """Drop the partial dataset; the destination is left as it was."""
        if self._finished:
            return
        self._finished = True
        self._release()
        discard_folder(self._partial)


class Dataset:
    """A dataset folder opened for reading; errors name the file and what was expected."""

    def __init__(self, folder: Path | str) -> None:
        self.folder = Path(folder)
        if not (self.folder / META).is_file():
            raise ConfigError(
                f"{self.folder}: not a dataset folder (no {META}; an interrupted or partial "
                "dataset has none)"
            )
        self.meta = _read_meta(self.folder / META)
        frames = _read_table(self.folder / FRAMES_CSV, ("frame", "t_s"))
        if not np.array_equal(frames[:, 0], np.arange(frames.shape[0])):
            raise ConfigError(
                f"{self.folder / FRAMES_CSV}: column 'frame' must count 0, 1, 2, ... in order"
            )
        self.frame_t_s = frames[:, 1]
        ft = _read_table(self.folder / FT_CSV, FT_COLUMNS)
        self.ft_t_s, self.ft_wrench = ft[:, 0], ft[:, 1:]
        self._video = self._open_video()
        truth_path = self.folder / TRUTH_CSV
        self.truth = _read_named_table(truth_path, len(self)) if truth_path.is_file() else None
        _check_meta_against_data(self)

    def __len__(self) -> int:
        return int(self.frame_t_s.size)

    def _open_video(self) -> VideoFile:
        path = self.folder / VIDEO
        try:
            video = VideoFile.open(path)
        except VideoError as exc:
            raise ConfigError(f"{path}: {exc}") from None
        if video.header_frames is not None and video.header_frames != len(self):
            raise ConfigError(
                f"{path}: the video's header says {video.header_frames} frames, but "
                f"{FRAMES_CSV} lists {len(self)}: the dataset is incomplete or damaged"
            )
        return video

    def frames(self) -> Iterator[tuple[int, float, np.ndarray]]:
        """(index, t_s, BGR image) for every frame, in order; a frame that is missing or does
        not decode is a ConfigError."""
        path = self.folder / VIDEO
        log = ReadLog()
        index = -1
        for index, (found, image) in enumerate(self._video.frames(log)):
            if found != index:
                raise ConfigError(
                    f"{path}: frames {index}-{found - 1} are missing or did not decode"
                )
            if index >= len(self):
                raise ConfigError(f"{path}: the video holds more frames than {FRAMES_CSV} lists")
            yield index, float(self.frame_t_s[index]), image
        if index + 1 < len(self):
            raise ConfigError(
                f"{path}: video ends at frame {index + 1}, but {FRAMES_CSV} lists "
                f"{len(self)} frames"
            )

    def gel_truth(self) -> tuple[np.ndarray, np.ndarray]:
        """The live gel's wrench on the object from the F/T readings: times (n,) s and
        wrenches (n, 6) in S, N and N*m (``gel_load_factor`` times the reading)."""
        return self.ft_t_s, self.meta.gel_load_factor * self.ft_wrench

    def in_interval(self, interval: tuple[float, float]) -> np.ndarray:
        """Mask of the frames captured in [start, end)."""
        return (self.frame_t_s >= interval[0]) & (self.frame_t_s < interval[1])


def _increasing(path: Path, name: str, t_s: np.ndarray) -> None:
    if t_s.size > 1 and not (np.diff(t_s) > 0).all():
        first = int(np.argmax(np.diff(t_s) <= 0)) + 1
        raise ConfigError(
            f"{path}: column '{name}' must increase from row to row; row {first + 1} "
            f"({t_s[first]!r}) does not come after {t_s[first - 1]!r}"
        )


def _read_table(path: Path, columns: tuple[str, ...]) -> np.ndarray:
    if not path.is_file():
        raise ConfigError(f"{path}: missing (expected a CSV with columns {','.join(columns)})")
    with open(path, newline="") as handle:
        header = next(csv.reader(handle), None)
    if header is None or tuple(header) != columns:
        raise ConfigError(f"{path}: expected the header {','.join(columns)}, got {header}")
    table = _numbers(path, len(columns))
    if table.shape[0] == 0 or not np.isfinite(table).all():
        raise ConfigError(f"{path}: expected finite numbers in every row, and at least one row")
    _increasing(path, "t_s", table[:, columns.index("t_s")])
    return table


def _numbers(path: Path, columns: int) -> np.ndarray:
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # "input contained no data"
            table = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    except ValueError as exc:
        raise ConfigError(f"{path}: expected numbers in every row ({exc})") from None
    if table.size and table.shape[1] != columns:
        raise ConfigError(f"{path}: expected {columns} columns in every row")
    return table.reshape(-1, columns)


def _read_named_table(path: Path, rows: int) -> dict[str, np.ndarray]:
    with open(path, newline="") as handle:
        header = next(csv.reader(handle), None)
    if not header or len(set(header)) != len(header) or not all(header):
        raise ConfigError(f"{path}: expected a header of distinct column names, got {header}")
    table = _numbers(path, len(header))
    if table.shape[0] != rows:
        raise ConfigError(f"{path}: expected one row per frame ({rows}), got {table.shape[0]}")
    return {name: table[:, i] for i, name in enumerate(header)}


def _interval(path: Path, key: str, value: Any) -> tuple[float, float]:
    if (
        not isinstance(value, list)
        or len(value) != 2
        or not all(isinstance(v, int | float) and not isinstance(v, bool) for v in value)
        or not all(math.isfinite(v) for v in value)
        or not value[0] < value[1]
    ):
        raise ConfigError(
            f"{path}: key '{key}': expected [t_start_s, t_end_s], finite and increasing, "
            f"got {value!r}"
        )
    return float(value[0]), float(value[1])


def _read_meta(path: Path) -> DatasetMeta:
    data = load_yaml(path)
    for key in _STRUCTURED_KEYS:
        if key not in data:
            raise ConfigError(f"{path}: missing key '{key}'")
    head = build(
        _MetaHead, {k: v for k, v in data.items() if k not in _STRUCTURED_KEYS}, source=str(path)
    )
    items = data["segments"]
    if items is None:
        items = []
    if not isinstance(items, list):
        raise ConfigError(f"{path}: key 'segments': expected a list of segments, got {items!r}")
    segments = tuple(
        build(Segment, item, source=str(path), prefix=f"segments[{i}].")
        for i, item in enumerate(items)
    )
    extras = data["extras"] or {}
    if not isinstance(extras, Mapping):
        raise ConfigError(f"{path}: key 'extras': expected a mapping, got {extras!r}")
    return DatasetMeta(
        sensor=head.sensor,
        source=head.source,
        gel_load_factor=head.gel_load_factor,
        reference=_interval(path, "reference", data["reference"]),
        open=None if data["open"] is None else _interval(path, "open", data["open"]),
        segments=segments,
        extras=extras,
    )


def _slack(t_s: np.ndarray) -> float:
    return _SLACK_INTERVALS * float(np.median(np.diff(t_s))) if t_s.size > 1 else 0.0


def _check_meta_against_data(dataset: Dataset) -> None:
    """The meta's intervals and segments must lie within the recorded frames and F/T
    readings, and hold frames: a dataset cut short (an interrupted recording) fails here."""
    meta_path = dataset.folder / META
    frames_t, ft_t = dataset.frame_t_s, dataset.ft_t_s
    frame_slack, ft_slack = _slack(frames_t), _slack(ft_t)
    for key, interval in (("reference", dataset.meta.reference), ("open", dataset.meta.open)):
        if interval is not None and not dataset.in_interval(interval).any():
            raise ConfigError(
                f"{meta_path}: key '{key}': no frame of {FRAMES_CSV} lies in {list(interval)} s "
                f"(frames span {frames_t[0]:g} to {frames_t[-1]:g} s)"
            )
    for i, segment in enumerate(dataset.meta.segments):
        span = f"[{segment.t_start_s:g}, {segment.t_end_s:g}] s"
        if (
            segment.t_start_s < frames_t[0] - frame_slack
            or segment.t_end_s > frames_t[-1] + frame_slack
        ):
            raise ConfigError(
                f"{meta_path}: key 'segments[{i}]': {span} lies outside the frames of "
                f"{FRAMES_CSV} ({frames_t[0]:g} to {frames_t[-1]:g} s): the dataset is "
                "incomplete (an interrupted recording?)"
            )
        if segment.t_start_s < ft_t[0] - ft_slack or segment.t_end_s > ft_t[-1] + ft_slack:
            raise ConfigError(
                f"{meta_path}: key 'segments[{i}]': {span} lies outside the F/T readings of "
                f"{FT_CSV} ({ft_t[0]:g} to {ft_t[-1]:g} s): the dataset is incomplete"
            )
        if not dataset.in_interval((segment.t_start_s, segment.t_end_s)).any():
            raise ConfigError(f"{meta_path}: key 'segments[{i}]': no frame lies in {span}")
