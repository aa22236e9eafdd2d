"""Fault injection for video files: cut a file short, or destroy one frame's JPEG data.

The files are real MJPG AVIs written by cv2.VideoWriter; the damage is done to their bytes,
the way a crash (truncation) or a bad disk block (overwritten bytes) does it.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

SOI = b"\xff\xd8\xff"  # a JPEG's start-of-image marker, then the first segment's marker


def write_mjpg(path: Path, frames: list[np.ndarray], fps: float = 25.0) -> Path:
    height, width = frames[0].shape[:2]
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"MJPG"), fps, (width, height))
    assert writer.isOpened()
    for frame in frames:
        writer.write(frame)
    writer.release()
    return path


def jpeg_offsets(path: Path) -> list[int]:
    """Byte offsets of each frame's JPEG data in the file, in order."""
    data = path.read_bytes()
    offsets, start = [], data.find(SOI)
    while start >= 0:
        offsets.append(start)
        start = data.find(SOI, start + 1)
    return offsets


def truncate_inside_frame(path: Path, frame: int) -> None:
    """Cut the file in the middle of frame ``frame``'s JPEG data (a crash while writing)."""
    offsets = jpeg_offsets(path)
    cut = (offsets[frame] + offsets[frame + 1]) // 2
    with open(path, "r+b") as handle:
        handle.truncate(cut)


def corrupt_frame(path: Path, frame: int, size: int = 600) -> None:
    """Overwrite the first ``size`` bytes of frame ``frame``'s JPEG data (its markers and
    tables) with zeros: that frame no longer decodes, the container around it is intact."""
    offset = jpeg_offsets(path)[frame]
    with open(path, "r+b") as handle:
        handle.seek(offset)
        handle.write(bytes(size))
