"""A LeRobot dataset's statistics as LeRobot computes them (lerobot 0.6.1,
``lerobot/datasets/compute_stats.py``; docs/EPISODES.md, "Statistics"):

* per episode: every numeric feature over all its rows; the video over
  ``sample_count(length)`` evenly spaced frames (``estimate_num_samples``: ``length ** 0.75``,
  at least 100 or the whole episode if shorter, at most 10 000), each frame first
  downsampled as ``auto_downsample_height_width`` does (a side of 300 px or more: every
  ``side // 150``-th pixel);
* over the dataset (``stats.json``), ``aggregate`` of the per-episode statistics as
  ``aggregate_feature_stats`` does: the min of the minimums, the max of the maximums, the
  count-weighted mean of the means, the pooled variance (each episode's variance plus its
  mean's squared distance to the overall mean, count-weighted), and each quantile the
  count-weighted mean of the episodes' quantiles (not the quantile of the pooled rows).

Quantiles per episode are exact here (``np.quantile``, linear); LeRobot's come from a
5000-bin histogram of each episode, so they agree to within a bin.
"""

from __future__ import annotations

import numpy as np

QUANTILES = (0.01, 0.10, 0.50, 0.90, 0.99)
QUANTILE_KEYS = tuple(f"q{round(q * 100):02d}" for q in QUANTILES)
MIN_SAMPLES, MAX_SAMPLES, SAMPLE_POWER = 100, 10_000, 0.75
DOWNSAMPLE_FROM_PX, DOWNSAMPLE_TO_PX = 300, 150

Stats = dict[str, np.ndarray]


def sample_count(length: int) -> int:
    """How many of an episode's ``length`` frames LeRobot takes image statistics on."""
    return max(min(MIN_SAMPLES, length), min(int(length**SAMPLE_POWER), MAX_SAMPLES))


def sample_indices(length: int) -> np.ndarray:
    """The frames (indices, ascending) those statistics are taken on: evenly spaced."""
    return np.round(np.linspace(0, length - 1, sample_count(length))).astype(int)


def downsampled(frame: np.ndarray) -> np.ndarray:
    """``frame`` (H x W x C) as LeRobot's image statistics see it: every ``step``-th pixel
    both ways, ``step = larger side // 150``, when the larger side is 300 px or more."""
    height, width = frame.shape[:2]
    if max(height, width) < DOWNSAMPLE_FROM_PX:
        return frame
    step = (width if width > height else height) // DOWNSAMPLE_TO_PX
    return frame[::step, ::step]


def numeric_stats(values: np.ndarray) -> Stats:
    """min, max, mean, std, count and the quantiles over the rows of ``values`` (n, k)."""
    stats = {
        "min": values.min(axis=0),
        "max": values.max(axis=0),
        "mean": values.mean(axis=0, dtype=np.float64),
        "std": values.std(axis=0, dtype=np.float64),
        "count": np.array([len(values)]),
    }
    for key, value in zip(QUANTILE_KEYS, np.quantile(values, QUANTILES, axis=0), strict=True):
        stats[key] = value
    return stats


def aggregate(episodes: list[Stats]) -> Stats:
    """One feature's statistics over the dataset from its per-episode ones (see the module
    doc); ValueError for none."""
    if not episodes:
        raise ValueError("no statistics to aggregate")
    counts = np.array([float(s["count"][0]) for s in episodes])
    total = counts.sum()
    means = np.stack([np.asarray(s["mean"], dtype=np.float64) for s in episodes])
    weights = counts.reshape((-1,) + (1,) * (means.ndim - 1))
    mean = (means * weights).sum(axis=0) / total
    variances = np.stack([np.asarray(s["std"], dtype=np.float64) ** 2 for s in episodes])
    variance = ((variances + (means - mean) ** 2) * weights).sum(axis=0) / total
    out: Stats = {
        "min": np.min(np.stack([s["min"] for s in episodes]), axis=0),
        "max": np.max(np.stack([s["max"] for s in episodes]), axis=0),
        "mean": mean,
        "std": np.sqrt(variance),
        "count": np.array([int(total)]),
    }
    for key in QUANTILE_KEYS:
        out[key] = (np.stack([s[key] for s in episodes]) * weights).sum(axis=0) / total
    return out


def aggregate_features(episodes: list[dict[str, Stats]]) -> dict[str, Stats]:
    """Every feature's dataset statistics from the episodes' (each: feature -> statistics)."""
    return {key: aggregate([e[key] for e in episodes]) for key in episodes[0]}
