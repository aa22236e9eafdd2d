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
"""

from __future__ import annotations

import csv
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import yaml

from drivers.config import ConfigError, load_yaml

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


@dataclass(frozen=True)
class Segment:
    """One experiment: torques about S's ``axis`` up to ``amplitude_nm`` during
    [t_start_s, t_end_s)."""

    axis: str
    amplitude_nm: float
    t_start_s: float
    t_end_s: float


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
    """Writes a dataset folder; frames and F/T rows go to disk as they come, and
    ``close()`` (or leaving the ``with`` block) writes ``meta.yaml``."""

    def __init__(self, folder: Path | str, meta: DatasetMeta, frame_rate_hz: float) -> None:
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        self.meta = meta
        self._rate = frame_rate_hz
        self._video: cv2.VideoWriter | None = None
        self._frames = open(self.folder / FRAMES_CSV, "w", newline="")
        self._frames_csv = csv.writer(self._frames)
        self._frames_csv.writerow(("frame", "t_s"))
        self._count = 0
        self._truth: Any = None
        self._truth_csv: Any = None

    def __enter__(self) -> DatasetWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def add_frame(self, t_s: float, image: np.ndarray) -> None:
        """Append a BGR uint8 frame captured at ``t_s``."""
        if self._video is None:
            height, width = image.shape[:2]
            self._video = cv2.VideoWriter(
                str(self.folder / VIDEO),
                cv2.CAP_OPENCV_MJPEG,
                cv2.VideoWriter_fourcc(*"MJPG"),
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
            self.folder / FT_CSV,
            table,
            delimiter=",",
            header=",".join(FT_COLUMNS),
            comments="",
            fmt="%.9g",
        )

    def add_truth(self, row: Mapping[str, float]) -> None:
        """Append the simulator's state for the latest frame (simulated datasets only)."""
        if self._truth is None:
            self._truth = open(self.folder / TRUTH_CSV, "w", newline="")
            self._truth_csv = csv.DictWriter(self._truth, fieldnames=list(row))
            self._truth_csv.writeheader()
        self._truth_csv.writerow({k: repr(float(v)) for k, v in row.items()})

    def close(self) -> None:
        if self._video is not None:
            self._video.release()
            self._video = None
        for handle in (self._frames, self._truth):
            if handle is not None and not handle.closed:
                handle.close()
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
        (self.folder / META).write_text(yaml.safe_dump(document, sort_keys=False))


class Dataset:
    """A dataset folder opened for reading; errors name the file and what was expected."""

    def __init__(self, folder: Path | str) -> None:
        self.folder = Path(folder)
        if not (self.folder / META).is_file():
            raise ConfigError(f"{self.folder}: not a dataset folder (no {META})")
        self.meta = _read_meta(self.folder / META)
        frames = _read_table(self.folder / FRAMES_CSV, ("frame", "t_s"))
        self.frame_t_s = frames[:, 1]
        ft = _read_table(self.folder / FT_CSV, FT_COLUMNS)
        self.ft_t_s, self.ft_wrench = ft[:, 0], ft[:, 1:]
        truth_path = self.folder / TRUTH_CSV
        self.truth = _read_named_table(truth_path) if truth_path.is_file() else None

    def __len__(self) -> int:
        return int(self.frame_t_s.size)

    def frames(self) -> Iterator[tuple[int, float, np.ndarray]]:
        """(index, t_s, BGR image) for every frame, in order."""
        path = self.folder / VIDEO
        capture = cv2.VideoCapture(str(path))
        if not capture.isOpened():
            raise ConfigError(f"{path}: cannot open the tactile video")
        try:
            for index, t_s in enumerate(self.frame_t_s):
                ok, image = capture.read()
                if not ok:
                    raise ConfigError(
                        f"{path}: video ends at frame {index}, but {FRAMES_CSV} lists "
                        f"{len(self)} frames"
                    )
                yield index, float(t_s), image
        finally:
            capture.release()

    def gel_truth(self) -> tuple[np.ndarray, np.ndarray]:
        """The live gel's wrench on the object from the F/T readings: times (n,) s and
        wrenches (n, 6) in S, N and N*m (``gel_load_factor`` times the reading)."""
        return self.ft_t_s, self.meta.gel_load_factor * self.ft_wrench

    def in_interval(self, interval: tuple[float, float]) -> np.ndarray:
        """Mask of the frames captured in [start, end)."""
        return (self.frame_t_s >= interval[0]) & (self.frame_t_s < interval[1])


def _read_table(path: Path, columns: tuple[str, ...]) -> np.ndarray:
    if not path.is_file():
        raise ConfigError(f"{path}: missing (expected a CSV with columns {','.join(columns)})")
    with open(path, newline="") as handle:
        header = next(csv.reader(handle), None)
    if header is None or tuple(header) != columns:
        raise ConfigError(f"{path}: expected the header {','.join(columns)}, got {header}")
    table = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    if table.shape[0] == 0 or not np.isfinite(table).all():
        raise ConfigError(f"{path}: expected finite numbers in every row")
    return table


def _read_named_table(path: Path) -> dict[str, np.ndarray]:
    with open(path, newline="") as handle:
        header = next(csv.reader(handle))
    table = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    return {name: table[:, i] for i, name in enumerate(header)}


def _interval(path: Path, key: str, value: Any) -> tuple[float, float]:
    if (
        not isinstance(value, list)
        or len(value) != 2
        or not all(isinstance(v, int | float) for v in value)
        or not value[0] < value[1]
    ):
        raise ConfigError(f"{path}: key '{key}': expected [t_start_s, t_end_s], got {value!r}")
    return float(value[0]), float(value[1])


def _read_meta(path: Path) -> DatasetMeta:
    data = load_yaml(path)
    if data.get("format") != FORMAT:
        raise ConfigError(f"{path}: key 'format': expected '{FORMAT}', got {data.get('format')!r}")
    required = ("sensor", "source", "gel_load_factor", "reference", "open", "segments", "extras")
    for key in required:
        if key not in data:
            raise ConfigError(f"{path}: missing key '{key}'")
    factor = data["gel_load_factor"]
    if not isinstance(factor, int | float) or not -1.0 <= factor <= 1.0 or factor == 0:
        raise ConfigError(
            f"{path}: key 'gel_load_factor': expected a non-zero number in [-1, 1], got {factor!r}"
        )
    segments = []
    for i, item in enumerate(data["segments"] or []):
        keys = ("axis", "amplitude_nm", "t_start_s", "t_end_s")
        if not isinstance(item, dict) or sorted(item) != sorted(keys):
            raise ConfigError(f"{path}: key 'segments[{i}]': expected the keys {list(keys)}")
        if item["axis"] not in ("x", "y", "z"):
            raise ConfigError(
                f"{path}: key 'segments[{i}].axis': expected x, y or z, got {item['axis']!r}"
            )
        start, end = _interval(path, f"segments[{i}]", [item["t_start_s"], item["t_end_s"]])
        segments.append(Segment(item["axis"], float(item["amplitude_nm"]), start, end))
    return DatasetMeta(
        sensor=str(data["sensor"]),
        source=str(data["source"]),
        gel_load_factor=float(factor),
        reference=_interval(path, "reference", data["reference"]),
        open=None if data["open"] is None else _interval(path, "open", data["open"]),
        segments=tuple(segments),
        extras=data["extras"] or {},
    )
