"""One run's episode: ``EpisodeRecording`` opens the file with the run's metadata and the
resolved task attached, gives the run path its tap and its observer, and closes the file
with the outcome.

    recording = EpisodeRecording.open(path, task_raw, task=..., seed=..., ...)
    run_task(..., episode=recording)        # taps the wrench source, observes the ticks
    recording.close({"reason": ..., ...})   # the outcome metadata, then the footer
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

from controller.episode.recorder import RecordingSource, TickLogger
from controller.episode.topics import ATTACHMENT_TASK, FORMAT_VERSION
from controller.episode.writer import FLUSH_INTERVAL_S, QUEUE_SIZE, EpisodeWriter, Listener
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
    """An open episode (see the module doc): ``writer`` and the ``options``."""

    def __init__(self, writer: EpisodeWriter, options: EpisodeOptions) -> None:
        self.writer = writer
        self.options = options

    @classmethod
    def open(
        cls,
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
        listeners: Sequence[Listener] = (),
    ) -> EpisodeRecording:
        """Create the episode file ``path`` (FileExistsError if it exists) with the
        ``episode`` metadata and the resolved task (``task_raw``) attached as YAML;
        ``listeners`` get every record as written (``EpisodeWriter``)."""
        options = options or EpisodeOptions()
        info = {
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
            "started_utc": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
            "tactile_image_format": options.image_format,
            "jpeg_quality": str(options.jpeg_quality),
            "queue_size": str(options.queue_size),
            "flush_interval_s": str(options.flush_interval_s),
        }
        task_yaml = yaml.safe_dump(plain(task_raw), sort_keys=False).encode()
        writer = EpisodeWriter(
            path,
            info,
            {ATTACHMENT_TASK: ("application/yaml", task_yaml)},
            queue_size=options.queue_size,
            flush_interval_s=options.flush_interval_s,
            listeners=listeners,
        )
        return cls(writer, options)

    def tap(self, source: WrenchSource, clock: Clock) -> RecordingSource:
        """``source`` wrapped so every frame, field, estimate and call is recorded."""
        return RecordingSource(
            source,
            self.writer,
            clock,
            image_format=self.options.image_format,
            jpeg_quality=self.options.jpeg_quality,
        )

    def observer(self) -> TickLogger:
        """The loop's observer that records each tick."""
        return TickLogger(self.writer)

    def close(self, outcome: Mapping[str, str] | None = None) -> None:
        """Write the outcome metadata and finish the file (idempotent)."""
        self.writer.close(outcome)
