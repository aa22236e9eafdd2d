"""Recorded tactile video read frame by frame, with every loss of frames accounted for.

OpenCV (FFmpeg backend) hides damage: a frame whose data does not decode ends the stream
(the frames after it are only found by reading on), a damaged frame may be patched, and a
truncated file simply ends early. The decoders' own messages are kept off the terminal
(controller/offline/quiet_decoding.py). This reader reads on past failures and numbers each frame
it returns by the container's presentation time (``round(pts * fps)``; by its position,
counting the failed reads, when the container gives no usable time), so a lost frame
leaves a gap in the numbers and the frames after it keep their true times. After a pass,
``ReadLog.damage`` lists what is missing: gaps in the numbering, and an end that disagrees
with the frame count in the container's header (a truncated file). The callers decide
whether that is an error (datasets, and ``tactile estimate`` by default) or a warning.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

from controller.offline.quiet_decoding import native_stderr_muted

UNREADABLE_IN_A_ROW = 50  # failed reads in a row that end a pass (the end of the file)


class VideoError(ValueError):
    """The file is not a video OpenCV can open, or its first frame does not decode."""


@dataclass
class ReadLog:
    """What one pass over a video returned: ``read`` frames, ``last`` the number of the
    last one (-1: none), ``gaps`` the (first, last) numbers of each run of missing frames."""

    read: int = 0
    last: int = -1
    gaps: list[tuple[int, int]] = field(default_factory=list)

    def record(self, number: int) -> None:
        if number > self.last + 1:
            self.gaps.append((self.last + 1, number - 1))
        self.read += 1
        self.last = number

    def damage(self, header_frames: int | None) -> list[str]:
        """One message per kind of loss; empty when the pass read a whole, intact video."""
        problems = []
        if self.gaps:
            lost = sum(b - a + 1 for a, b in self.gaps)
            where = ", ".join(f"{a}" if a == b else f"{a}-{b}" for a, b in self.gaps[:5])
            more = f" and {len(self.gaps) - 5} more runs" if len(self.gaps) > 5 else ""
            problems.append(f"{lost} frames are missing or did not decode (frames {where}{more})")
        if header_frames is not None and self.last + 1 != header_frames:
            problems.append(
                f"its header says {header_frames} frames, but it ends after frame "
                f"{self.last} ({self.read} frames read): the file is truncated or damaged"
            )
        return problems


@dataclass(frozen=True)
class VideoFile:
    """A video file: its path, the frame count (None: unknown) and frame rate (Hz; None:
    unknown) from its header."""

    path: Path
    header_frames: int | None
    fps: float | None

    @classmethod
    def open(cls, path: Path | str) -> VideoFile:
        """Check that ``path`` opens and its first frame decodes; read the header."""
        path = Path(path)
        with native_stderr_muted():
            capture = cv2.VideoCapture(str(path))
        try:
            with native_stderr_muted():
                ok = capture.isOpened() and capture.read()[0]
            count = capture.get(cv2.CAP_PROP_FRAME_COUNT) if ok else 0.0
            fps = capture.get(cv2.CAP_PROP_FPS) if ok else 0.0
        finally:
            capture.release()
        if not ok:
            raise VideoError(f"cannot read video '{path}': OpenCV cannot open or decode it")
        good_count = math.isfinite(count) and count >= 1
        good_fps = math.isfinite(fps) and fps > 0
        return cls(path, int(round(count)) if good_count else None, fps if good_fps else None)

    def frames(self, log: ReadLog | None = None) -> Iterator[tuple[int, np.ndarray]]:
        """(frame number, BGR image) of every frame that decodes, in order; ``log`` (if
        given) records the pass. OpenCV reports a frame that does not decode as the end of
        the stream; reading on finds the frames after it, so the pass ends only after
        ``UNREADABLE_IN_A_ROW`` failed reads in a row."""
        log = ReadLog() if log is None else log
        with native_stderr_muted():
            capture = cv2.VideoCapture(str(self.path))
        failures = 0
        try:
            while failures < UNREADABLE_IN_A_ROW:
                with native_stderr_muted():
                    ok, image = capture.read()
                if not ok or image is None:
                    failures += 1
                    continue
                number = self._number(capture.get(cv2.CAP_PROP_POS_MSEC), log.last, failures)
                failures = 0
                log.record(number)
                yield number, image
        finally:
            capture.release()

    def _number(self, pts_ms: float, previous: int, failures: int) -> int:
        """By the presentation time when the container gives one that moves forward, else
        the next number after the ``failures`` frames that did not decode."""
        following = previous + 1 + failures
        if self.fps is None or not math.isfinite(pts_ms):
            return following
        number = round(pts_ms * 1e-3 * self.fps)
        return number if number > previous else following
