"""The tactile video of a LeRobot export: H.264 in MP4 through PyAV, one frame per dataset
frame, and the video ``info`` block LeRobot writes into ``meta/info.json``.

Encoding. ``libx264`` (the PyAV wheel's H.264 encoder; LeRobot accepts ``h264``, ``hevc`` and
``libsvtav1``), ``yuv420p`` (what every decoder plays), a keyframe every ``GOP_FRAMES``
frames (LeRobot's default ``g=2``: a frame is decoded after at most one other, so random
access by timestamp stays cheap), constant quality ``CRF``. Frame ``i`` of the file has
presentation time ``i / fps`` s exactly (time base ``1 / fps``): the episodes of one export
follow each other in one file, and an episode's frames start at its ``from_timestamp``.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from fractions import Fraction
from pathlib import Path
from typing import Any, cast

import av
import numpy as np

CODEC = "libx264"
PIX_FMT = "yuv420p"
GOP_FRAMES = 2
CRF = 18
"""x264's constant rate factor: 18 is close to visually lossless on the gel's markers."""


class VideoWriter:
    """Appends RGB frames (uint8, H x W x 3) to an MP4 at ``fps``; frame ``i`` (counted over
    the whole file) is shown at ``i / fps`` s. Use through ``open_video``."""

    def __init__(self, container: Any, fps: int, width: int, height: int) -> None:
        self._container = container
        self._stream = container.add_stream(
            CODEC, rate=fps, options={"crf": str(CRF), "g": str(GOP_FRAMES)}
        )
        self._stream.width, self._stream.height = width, height
        self._stream.pix_fmt = PIX_FMT
        self._time_base = Fraction(1, fps)
        self.shape = (height, width, 3)
        self.frames = 0

    def write(self, rgb: np.ndarray) -> None:
        """Append one frame; ValueError if its shape or type differs from the video's."""
        if rgb.shape != self.shape or rgb.dtype != np.uint8:
            raise ValueError(
                f"expected a uint8 RGB frame of shape {self.shape}, got {rgb.dtype} {rgb.shape}"
            )
        frame = av.VideoFrame.from_ndarray(np.ascontiguousarray(rgb), format="rgb24")
        frame.pts, frame.time_base = self.frames, self._time_base
        self._container.mux(self._stream.encode(frame))
        self.frames += 1

    def finish(self) -> None:
        self._container.mux(self._stream.encode(None))


@contextmanager
def open_video(path: Path, fps: int, width: int, height: int) -> Iterator[VideoWriter]:
    """A ``VideoWriter`` on a new MP4 at ``path``, flushed and closed when the block ends."""
    with av.open(str(path), mode="w", format="mp4") as container:
        writer = VideoWriter(container, fps, width, height)
        yield writer
        writer.finish()


def video_info(path: Path) -> dict[str, object]:
    """The ``info`` of a video feature as LeRobot v3.0 records it (``get_video_info``): size,
    codec, pixel format, rate, channels, no depth map, no audio."""
    with av.open(str(path)) as container:
        stream = container.streams.video[0]
        return {
            "video.height": stream.height,
            "video.width": stream.width,
            "video.codec": stream.codec_context.codec.canonical_name,
            "video.pix_fmt": stream.pix_fmt,
            "video.is_depth_map": False,
            "video.fps": int(cast(Fraction, stream.base_rate)),  # the MP4s written here have one
            "video.channels": 3,
            "has_audio": len(container.streams.audio) > 0,
        }


def read_video(path: Path) -> Iterator[tuple[float, np.ndarray]]:
    """(presentation time in s, RGB uint8 frame) of every frame of the MP4 at ``path``."""
    with av.open(str(path)) as container:
        for frame in container.decode(video=0):
            assert frame.time is not None
            yield float(frame.time), frame.to_ndarray(format="rgb24")
