"""Speed against accuracy: every estimator configuration on the same datasets, its median
per-frame latency (one thread) against its tilt-torque RMSE after calibration.

The datasets are the Mini's calibration runs with each object (plate, square peg, round
peg) on realistic images, and the plate on a real capture (evaluation/experiments/run.py):
the pegs are the closer stand-ins for a USB stick, and a configuration that is best on a wide
plate need not be best under a narrow peg. Accuracy uses the frames of the tilt
experiments (x and y) and runs in worker processes; latency is timed afterwards on the plate
dataset, one configuration at a time, so the workers' contention does not distort it.

Our datasets come from our own gel model and renderer, so a configuration is eligible for the
front only if it also holds on data they did not make: the independent real-gel check
(evaluation/realgel, docs/BENCHMARKS.md: the real captures warped by an elastic half-space)
at 0.4 px of tilt motion, with and without pushing, must give every sequence a tilt R^2 of at
least ``REALGEL_TARGET_R2`` (the estimator issue's accuracy target). The front of all
configurations, eligible or not, is reported beside it."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import cv2
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.ticker import ScalarFormatter

from controller.offline.dataset import Dataset
from controller.offline.dataset_fit import (
    estimate_frames,
    fit_dataset,
    reference_frames,
    segment_mask,
)
from controller.tactile import EstimatorConfig, TactileEstimator
from core.sensor_profile import sensor_profile
from evaluation.realgel.check import Row, sequence_specs
from evaluation.realgel.sequences import SequenceSpec
from evaluation.realgel.textures import TEXTURES

PARETO_AXES = ("x", "y")
REALGEL_TARGET_R2 = 0.97
REALGEL_AMPLITUDE_PX = 0.4
REALGEL_SEED = 2  # the seed docs/BENCHMARKS.md reports (0 and 1 were for exploring)
REALGEL_QUICK_TEXTURES = ("gelsight_markers_a", "digit_background_a")


@dataclass(frozen=True)
class ParetoPoint:
    """``latency_ms``: median estimator time per frame; ``rmse_nmm``: mean over the datasets
    and tilt axes of the calibrated RMSE (N*mm); ``rmse_by_dataset``: that mean per dataset;
    ``r2``: the worst axis's R^2 over the datasets. A configuration that cannot run on a
    dataset (``markers`` on a markerless gel) scores an infinite RMSE there (and so in the
    mean) and an R^2 of -inf. ``realgel_r2``: the worst held-out tilt R^2 over the real-gel
    check's sequences (``realgel_specs``), -inf if it cannot run on one of them.
    ``slip_recall``: the slip detector's worse recall (incipient or gross) on the slip
    sequences (evaluation/experiments/slip_eval.py), measured for the eligible configurations only
    (None for the others)."""

    label: str
    latency_ms: float
    p90_ms: float
    rmse_nmm: float
    r2: float
    rmse_by_dataset: dict[str, float]
    realgel_r2: float
    slip_recall: float | None = None

    @property
    def eligible(self) -> bool:
        """Whether the configuration meets the accuracy target on the real-gel check."""
        return meets_realgel_target(self.realgel_r2)


def meets_realgel_target(realgel_r2: float) -> bool:
    """A worst real-gel R^2 at or above ``REALGEL_TARGET_R2``: eligible for the front."""
    return realgel_r2 >= REALGEL_TARGET_R2


@dataclass(frozen=True)
class Accuracy:
    """What a worker measures for one configuration (the fields as in ``ParetoPoint``)."""

    label: str
    rmse_nmm: float
    r2: float
    rmse_by_dataset: dict[str, float]


def accuracy(folders: tuple[Path, ...], label: str, config: EstimatorConfig) -> Accuracy:
    """Calibrated tilt-torque accuracy of one configuration over the tilt experiments of the
    datasets in ``folders`` (run in a worker process)."""
    cv2.setNumThreads(1)
    by_dataset, worst = {}, 1.0
    for folder in folders:
        dataset = Dataset(folder)
        tilt = (dataset.frame_t_s >= dataset.meta.reference[1]) & np.any(
            [segment_mask(dataset, dataset.frame_t_s, axis) for axis in PARETO_AXES], axis=0
        )
        frames = (f for f in dataset.frames() if tilt[f[0]])
        reference = reference_frames(dataset, dataset.meta.reference)
        try:
            series = estimate_frames(frames, reference, _estimator(config, dataset), _open(dataset))
        except ValueError:  # cannot run on this gel (markers on a markerless one)
            by_dataset[folder.name], worst = math.inf, -math.inf
            continue
        fits = fit_dataset(dataset, series, PARETO_AXES)
        by_dataset[folder.name] = float(np.mean([fits[(a, "ours")].rmse for a in PARETO_AXES]))
        worst = min([worst, *(fits[(a, "ours")].r2 for a in PARETO_AXES)])
    by_dataset = {name: rmse * 1e3 for name, rmse in by_dataset.items()}
    return Accuracy(label, float(np.mean(list(by_dataset.values()))), worst, by_dataset)


def latency(folder: Path, config: EstimatorConfig, frames: int) -> tuple[float, float]:
    """Median and p90 estimator time per frame, ms, over the first ``frames`` frames after
    the reference, on one thread; run it with nothing else busy."""
    cv2.setNumThreads(1)
    dataset = Dataset(folder)
    start = dataset.meta.reference[1]
    chosen = (f for f in dataset.frames() if f[1] >= start)
    sample = [next(chosen) for _ in range(min(frames, int((dataset.frame_t_s >= start).sum())))]
    reference = reference_frames(dataset, dataset.meta.reference)
    series = estimate_frames(sample, reference, _estimator(config, dataset), _open(dataset))
    return float(np.median(series.latency_ms)), float(np.percentile(series.latency_ms, 90))


def _open(dataset: Dataset) -> list[np.ndarray] | None:
    """The dataset's open-gel frames (before the grasp), or None if it has none."""
    interval = dataset.meta.open
    return None if interval is None else reference_frames(dataset, interval)


def _estimator(config: EstimatorConfig, dataset: Dataset) -> TactileEstimator:
    """An estimator with ``config`` (one of the compared set) for the dataset's sensor."""
    return TactileEstimator(config, sensor_profile(dataset.meta.sensor))


def realgel_specs(quick: bool) -> list[SequenceSpec]:
    """The real-gel check's sequences that gate the front: every capture (two with ``quick``),
    tilt about x and y, with and without pushing, at ``REALGEL_AMPLITUDE_PX``, 160 frames (24
    with ``quick``), seed ``REALGEL_SEED``."""
    textures = REALGEL_QUICK_TEXTURES if quick else tuple(TEXTURES)
    return sequence_specs(textures, [REALGEL_AMPLITUDE_PX], 24 if quick else 160, REALGEL_SEED)


def worst_realgel_r2(rows: list[Row], label: str) -> float:
    """The worst R^2 of ``label``'s rows; -inf if it could not run on a sequence."""
    scores = [row.r2 for row in rows if row.estimator == label]
    if not scores:
        raise ValueError(f"no real-gel rows for {label!r}")
    return -math.inf if any(math.isnan(r) for r in scores) else min(scores)


def _objectives(p: ParetoPoint, with_slip: bool) -> tuple[float, ...]:
    """What ``beating`` minimises: latency, RMSE and, ``with_slip``, the slip recall's
    shortfall."""
    slip = () if not with_slip else (-(p.slip_recall if p.slip_recall is not None else 0.0),)
    return (p.latency_ms, p.rmse_nmm, *slip)


def beating(points: list[ParetoPoint], p: ParetoPoint, with_slip: bool = True) -> list[ParetoPoint]:
    """The points at least as good as ``p`` on every objective (latency, tilt RMSE and,
    ``with_slip``, slip recall) and better on one."""
    mine = _objectives(p, with_slip)
    scored = [(q, _objectives(q, with_slip)) for q in points]
    return [
        q
        for q, theirs in scored
        if theirs != mine and all(a <= b for a, b in zip(theirs, mine, strict=True))
    ]


def front(points: list[ParetoPoint], eligible_only: bool = True) -> list[ParetoPoint]:
    """The points nothing beats (sorted by latency). ``eligible_only``: among the
    configurations meeting the real-gel target, on latency, tilt RMSE and slip recall;
    otherwise among all, on latency and tilt RMSE only (slip is measured for the eligible)."""
    points = [p for p in points if p.eligible or not eligible_only]
    return sorted(
        (p for p in points if not beating(points, p, with_slip=eligible_only)),
        key=lambda p: p.latency_ms,
    )


def pareto_chart(points: list[ParetoPoint], path: Path, title: str) -> None:
    """Left: every configuration that runs on all datasets (log-log); right: a zoom on the
    most accurate ones (RMSE within 1.5x the best), where the front lies. Blue: on the
    front; crosses: miss the real-gel target; red: the paper's; green: the default."""
    shown = [p for p in points if math.isfinite(p.rmse_nmm)]  # the table lists the rest
    best = min(p.rmse_nmm for p in shown)
    close = [p for p in shown if p.rmse_nmm <= 1.5 * best]
    on_front = front(points)
    fig, (overview, zoom) = plt.subplots(1, 2, figsize=(14, 6))
    _scatter(overview, shown, on_front, labelled=[p for p in shown if p not in close])
    _scatter(zoom, close, on_front, labelled=close)
    overview.axhspan(0.0, 1.5 * best, color="tab:blue", alpha=0.06, label="zoomed on the right")
    overview.set_yscale("log")
    line = [p for p in on_front if not beating(on_front, p, with_slip=False)]
    zoom.plot([p.latency_ms for p in line], [p.rmse_nmm for p in line], "b--", lw=0.8)
    overview.set_xscale("log")
    for axis in (overview.xaxis, overview.yaxis):
        axis.set_major_formatter(ScalarFormatter())
    overview.yaxis.set_minor_formatter(ScalarFormatter())
    overview.set_xlabel("median latency per frame, one thread (ms, log)")
    zoom.set_xlabel("median latency per frame, one thread (ms)")
    for ax in (overview, zoom):
        ax.grid(True, which="both", alpha=0.3)
    overview.set_ylabel("tilt-torque RMSE after calibration (N*mm; mean of tau_x, tau_y, datasets)")
    overview.scatter([], [], marker="x", color="tab:gray", label="misses the real-gel target")
    overview.scatter([], [], marker="o", color="tab:blue", label="on the front")
    overview.legend(fontsize=8, loc="upper right")
    overview.set_title(title, fontsize=10)
    zoom.set_title(
        f"the most accurate; front: real-gel R^2 >= {REALGEL_TARGET_R2}, on speed, tilt and\n"
        "slip recall (dashed: its speed-accuracy corners)",
        fontsize=9,
    )
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def _scatter(ax, points: list[ParetoPoint], on_front: list[ParetoPoint], labelled) -> None:
    names = {p.label for p in on_front}
    for p in points:
        bold = p.label.startswith("**")
        colour = (
            "tab:red"
            if "paper" in p.label
            else "tab:green"
            if bold
            else ("tab:blue" if p.label in names else "tab:gray")
        )
        ax.scatter(
            p.latency_ms,
            p.rmse_nmm,
            s=60 if bold else 25,
            color=colour,
            marker="o" if p.eligible else "x",
            zorder=3,
        )
        if p in labelled:
            ax.annotate(
                p.label.replace("**", "").split(" (")[0],
                (p.latency_ms, p.rmse_nmm),
                fontsize=7,
                xytext=(4, 3),
                textcoords="offset points",
            )
