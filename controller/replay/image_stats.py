"""Streaming statistics of RGB uint8 frames, in bounded memory: ``ImageStats``.

LeRobot's image statistics of an episode are per channel over the pixels of its sampled
frames (controller/replay/lerobot_stats.py says which), scaled to [0, 1]: min, max, mean,
std and the quantiles q01, q10, q50, q90, q99, each of shape (3, 1, 1), and ``count`` (the
frames). A uint8 channel has 256 values, so a histogram of 256 counts per channel holds
everything these need: they come out as NumPy gives them on the stacked pixels
(``np.quantile``'s linear interpolation included; equal to float rounding), whatever the
number of frames, in 3 x 256 integers instead of every sampled pixel as float64 (the export
held 0.45 GB of them per episode).
"""

from __future__ import annotations

import numpy as np

from controller.replay.lerobot_stats import QUANTILE_KEYS, QUANTILES

LEVELS = 256


class ImageStats:
    """Per-channel histograms of the frames added (H x W x 3, uint8)."""

    def __init__(self) -> None:
        self.counts = np.zeros((3, LEVELS), dtype=np.int64)
        self.frames = 0

    def add(self, frame: np.ndarray) -> None:
        """Count the pixels of ``frame`` (H x W x 3 uint8, RGB)."""
        if frame.dtype != np.uint8 or frame.ndim != 3 or frame.shape[2] != 3:
            raise ValueError(f"expected an H x W x 3 uint8 frame, got {frame.dtype} {frame.shape}")
        for channel in range(3):
            self.counts[channel] += np.bincount(frame[:, :, channel].ravel(), minlength=LEVELS)
        self.frames += 1

    def merge(self, other: ImageStats) -> None:
        """Add ``other``'s counts to these."""
        self.counts += other.counts
        self.frames += other.frames

    def stats(self) -> dict[str, np.ndarray]:
        """min, max, mean, std and the quantiles per channel in [0, 1], each (3, 1, 1), and
        ``count`` (the frames, shape (1,)). ValueError without frames."""
        if self.frames == 0:
            raise ValueError("no frames to take statistics of")
        values = np.arange(LEVELS, dtype=np.float64) / (LEVELS - 1)
        out: dict[str, list[float]] = {k: [] for k in ("min", "max", "mean", "std")}
        out |= {key: [] for key in QUANTILE_KEYS}
        for counts in self.counts:
            present = np.flatnonzero(counts)
            total = int(counts.sum())
            mean = float(np.dot(counts, values) / total)
            out["min"].append(float(values[present[0]]))
            out["max"].append(float(values[present[-1]]))
            out["mean"].append(mean)
            out["std"].append(float(np.sqrt(np.dot(counts, (values - mean) ** 2) / total)))
            for key, q in zip(QUANTILE_KEYS, QUANTILES, strict=True):
                out[key].append(_quantile(counts, values, total, q))
        stats = {k: np.array(v).reshape(3, 1, 1) for k, v in out.items()}
        return stats | {"count": np.array([self.frames])}


def _quantile(counts: np.ndarray, values: np.ndarray, total: int, q: float) -> float:
    """``np.quantile`` (linear) of the ``total`` sorted values the histogram stands for."""
    position = (total - 1) * q
    below = int(np.floor(position))
    ends = np.cumsum(counts)  # the sorted index after the last pixel of each level

    def at(index: int) -> float:
        return float(values[np.searchsorted(ends, index, side="right")])

    low = at(below)
    high = at(min(below + 1, total - 1))
    return low + (position - below) * (high - low)
