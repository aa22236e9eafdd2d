"""Averaging the next pushed frames into one image: the open gel's capture and the
reference's (controller/tactile/estimator.py)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class MeanImage:
    """The mean of some frames' working images (BGR uint8 (H, W, 3) at the sensor profile's
    resolution), and ``frame_shape``, the frames' own (rows, cols) in px before resizing: the
    size later frames must have."""

    image: np.ndarray
    frame_shape: tuple[int, ...]

    @classmethod
    def of_sum(cls, total: np.ndarray, count: int, frame_shape: tuple[int, ...]) -> MeanImage:
        """The mean of ``count`` working images summed into ``total`` (float32)."""
        # Round half to even: the mean of 2 integer frames ends in .5 half the time, and
        # rounding those up would brighten the image by 0.25 grey levels, which dense flow on
        # a smooth gel reads as motion.
        return cls(np.clip(np.rint(total / count), 0, 255).astype(np.uint8), frame_shape)


class FrameCapture:
    """Sums the working images of the next ``frames_left`` frames, then keeps their mean as
    ``result`` (None before the first capture completes or is ``set``)."""

    def __init__(self) -> None:
        self.frames_left = 0
        self.result: MeanImage | None = None
        self._count = 0
        self._sum: np.ndarray | None = None
        self._frame_shape: tuple[int, ...] | None = None

    @property
    def active(self) -> bool:
        """True while frames are still to come."""
        return self.frames_left > 0

    @property
    def frame_shape(self) -> tuple[int, ...] | None:
        """The (rows, cols) the next frame must have: the capture's first frame's; None
        before it."""
        return self._frame_shape if self._count else None

    def start(self, n_frames: int) -> None:
        """Capture the next ``n_frames`` frames (>= 1); ``result`` stays until they are in."""
        self.frames_left = n_frames
        self._count = 0
        self._sum = None

    def stop(self) -> None:
        """Stop capturing; ``result`` stays."""
        self.frames_left = 0

    def set(self, result: MeanImage) -> None:
        """Use ``result`` now, stopping any capture."""
        self.result = result
        self.frames_left = 0

    def add(
        self,
        image: np.ndarray,
        frame_shape: tuple[int, ...],
        accept: Callable[[MeanImage], None] | None = None,
    ) -> None:
        """Add one frame's working ``image`` (the frame's own (rows, cols): ``frame_shape``).
        On the last frame the mean is handed to ``accept`` first, then becomes ``result``: if
        ``accept`` raises, nothing changes (the next frame is the last again)."""
        total = image.astype(np.float32)
        if self._sum is not None:
            total += self._sum
        captured = self.frame_shape
        shape = frame_shape if captured is None else captured
        last = self.frames_left == 1
        if last:
            mean = MeanImage.of_sum(total, self._count + 1, shape)
            if accept is not None:
                accept(mean)
            self.result = mean
        self._frame_shape = shape
        self._sum = None if last else total
        self._count += 1
        self.frames_left -= 1
