"""One run's episode: ``EpisodeRecording`` creates the file with the run's metadata, the
resolved task and the run's calibration attached when the run starts, gives the run path its
tap and its observer, and closes the file with the outcome.

    recording = EpisodeRecording(path, task_raw, task=..., seed=..., ...)
    run_task(..., episode=recording)        # once the devices are connected: start(), then
                                            # it taps the wrench source and observes ticks
    recording.close({"reason": ..., ...})   # the outcome metadata, then the footer

A run that never starts (a device that does not connect) leaves no file.
"""

from __future__ import annotations

import datetime
import json
import platform
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from controller.episode.recorder import Mount, RecordingSource, TickLogger
from controller.episode.topics import (
    ATTACHMENT_CALIBRATION,
    ATTACHMENT_MEDIA_TYPE,
    ATTACHMENT_TASK,
    FORMAT_VERSION,
)
from controller.episode.writer import FLUSH_INTERVAL_S, QUEUE_SIZE, EpisodeWriter, Listener
from controller.tactile.calibration import Calibration
from controller.tactile.wrench_source import WrenchSource
from core.clock import Clock
from core.provenance import git_revision, package_version

EPISODE_FILE = "episode.mcap"
"""The episode's name in a run's output folder."""


@dataclass(frozen=True)
class EpisodeOptions:
    """How an episode is written. ``image_format``: 'jpeg' (default; lossy, small) or
    'png' (lossless: re-estimation reproduces the logged estimates exactly, about ten times
    the size: docs/EPISODES.md); ``jpeg_quality`` 1..100; ``queue_size`` (records);
    ``flush_interval_s``."""

    image_format: str = "jpeg"
    jpeg_quality: int = 80
    queue_size: int = QUEUE_SIZE
    flush_interval_s: float = FLUSH_INTERVAL_S

    def __post_init__(self) -> None:
        if self.image_format not in ("jpeg", "png"):
            raise ValueError(f"image_format: expected 'jpeg' or 'png', got {self.image_format!r}")
        if not 1 <= self.jpeg_quality <= 100:
            raise ValueError(f"jpeg_quality: expected 1..100, got {self.jpeg_quality!r}")
        if self.queue_size < 1:
            raise ValueError(f"queue_size: expected at least 1, got {self.queue_size!r}")
        if not 0.0 < self.flush_interval_s <= 10.0:
            raise ValueError(f"flush_interval_s: expected (0, 10] s, got {self.flush_interval_s!r}")


def plain(value: Any) -> Any:
    """``value`` with every mapping a dict and every sequence a list (for YAML and JSON)."""
    if isinstance(value, Mapping):
        return {str(k): plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    return value


def machine_description() -> str:
    """The host, its architecture and OS, and Python's version."""
    return (
        f"{platform.node()}; {platform.machine()}; {platform.system()} {platform.release()}; "
        f"Python {platform.python_version()}"
    )


class EpisodeRecording:
    """One run's episode (see the module doc): ``path``, the ``options``, and once started
    the ``writer``. ``listeners`` get every record as the writer writes it (``EpisodeWriter``;
    the live view and the Foxglove live stream)."""

    def __init__(
        self,
        path: Path,
        task_raw: Mapping[str, Any],
        *,
        task: str,
        task_file: Path | str,
        overrides: Sequence[str],
        seed: int,
        controller: str,
        backend: str,
        options: EpisodeOptions | None = None,
        calibration: Calibration | None = None,
        listeners: Sequence[Listener] = (),
    ) -> None:
        options = options or EpisodeOptions()
        self.path = Path(path)
        self.options = options
        self.listeners = tuple(listeners)
        self.writer: EpisodeWriter | None = None
        self._info = {
            "format_version": FORMAT_VERSION,
            "task": task,
            "task_file": str(task_file),
            "overrides": json.dumps(list(overrides)),
            "seed": str(seed),
            "controller": controller,
            "backend": backend,
            "package_version": package_version(),
            "git_revision": git_revision(),
            "machine": machine_description(),
            "tactile_image_format": options.image_format,
            "jpeg_quality": str(options.jpeg_quality),
            "queue_size": str(options.queue_size),
            "flush_interval_s": str(options.flush_interval_s),
        }
        self._attachments = {
            ATTACHMENT_TASK: (
                ATTACHMENT_MEDIA_TYPE,
                yaml.safe_dump(plain(task_raw), sort_keys=False).encode(),
            )
        }
        if calibration is not None:
            self._attachments[ATTACHMENT_CALIBRATION] = (
                ATTACHMENT_MEDIA_TYPE,
                calibration.to_yaml().encode(),
            )

    def start(self, clock: Clock | None = None) -> EpisodeWriter:
        """Create the episode file (FileExistsError if it exists) with the ``episode``
        metadata (its ``started_utc`` now), the resolved task and the run's calibration (if
        any) attached as YAML. ``clock``: the loop's clock, whose time now fixes the offset
        from the loop's times to the log times (the wall clock; a loop time of 0 now if
        None)."""
        if self.writer is not None:
            raise RuntimeError(f"episode {self.path}: started already")
        started = datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds")
        self.writer = EpisodeWriter(
            self.path,
            {**self._info, "started_utc": started},
            self._attachments,
            queue_size=self.options.queue_size,
            flush_interval_s=self.options.flush_interval_s,
            listeners=self.listeners,
            loop_now_s=0.0 if clock is None else clock.now(),
        )
        return self.writer

    def _started(self) -> EpisodeWriter:
        if self.writer is None:
            raise RuntimeError(f"episode {self.path}: not started")
        return self.writer

    def tap(self, source: WrenchSource, clock: Clock, camera: object = None) -> RecordingSource:
        """``source`` wrapped so every frame, field, estimate and call is recorded; a
        ``camera`` that can compress its frames (``recorder.CompressingCamera``) is asked to,
        so the writer logs its JPEGs as they come."""
        return RecordingSource(
            source,
            self._started(),
            clock,
            image_format=self.options.image_format,
            jpeg_quality=self.options.jpeg_quality,
            camera=camera,
        )

    def observer(self, mount: Mount | None = None) -> TickLogger:
        """The loop's observer that records each tick (and ``/tf_static``: ``mount``, where
        the sensor sits on the tool, ``recorder.sensor_mount``, when given)."""
        return TickLogger(self._started(), mount)

    def close(self, outcome: Mapping[str, str] | None = None) -> None:
        """Write the outcome metadata and finish the file (idempotent; nothing if the
        recording never started)."""
        if self.writer is not None:
            self.writer.close(outcome)
