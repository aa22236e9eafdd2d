"""Speed against accuracy: every estimator configuration on the same dataset, its median
per-frame latency (one thread) against its tilt-torque RMSE after calibration. Accuracy runs
in worker processes; latency is timed afterwards, one configuration at a time, so the
workers' contention does not distort it."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import cv2
import matplotlib.pyplot as plt
import numpy as np

from controller.config import sensor_profile
from controller.tactile.dataset import Dataset
from controller.tactile.dataset_fit import (
    estimate_dataset,
    estimate_frames,
    fit_dataset,
    reference_frames,
)
from controller.tactile.settings import EstimatorConfig

PARETO_AXES = ("x", "y")


@dataclass(frozen=True)
class ParetoPoint:
    """``latency_ms``: median estimator time per frame; ``rmse_nmm``: mean over the tilt
    axes of the calibrated RMSE (N*mm); ``r2``: the worse axis's R^2."""

    label: str
    latency_ms: float
    p90_ms: float
    rmse_nmm: float
    r2: float


def accuracy(folder: Path, label: str, config: EstimatorConfig) -> tuple[str, float, float]:
    """(label, RMSE in N*mm, worst R^2) of one configuration on the whole dataset in
    ``folder`` (run in a worker process)."""
    cv2.setNumThreads(1)
    dataset = Dataset(folder)
    series = estimate_dataset(dataset, config, sensor_profile(dataset.meta.sensor))
    fits = fit_dataset(dataset, series)
    rmse = float(np.mean([fits[(axis, "ours")].rmse for axis in PARETO_AXES])) * 1e3
    return label, rmse, min(fits[(axis, "ours")].r2 for axis in PARETO_AXES)


def latency(folder: Path, config: EstimatorConfig, frames: int) -> tuple[float, float]:
    """Median and p90 estimator time per frame, ms, over the first ``frames`` frames after
    the reference, on one thread; run it with nothing else busy."""
    cv2.setNumThreads(1)
    dataset = Dataset(folder)
    start = dataset.meta.reference[1]
    chosen = (f for f in dataset.frames() if f[1] >= start)
    sample = [next(chosen) for _ in range(min(frames, int((dataset.frame_t_s >= start).sum())))]
    reference = reference_frames(dataset, dataset.meta.reference)
    series = estimate_frames(sample, reference, config, sensor_profile(dataset.meta.sensor))
    return float(np.median(series.latency_ms)), float(np.percentile(series.latency_ms, 90))


def front(points: list[ParetoPoint]) -> list[ParetoPoint]:
    """The points no other point beats on both latency and RMSE (sorted by latency)."""
    return sorted(
        (
            p
            for p in points
            if not any(
                q.latency_ms <= p.latency_ms
                and q.rmse_nmm <= p.rmse_nmm
                and (q.latency_ms < p.latency_ms or q.rmse_nmm < p.rmse_nmm)
                for q in points
            )
        ),
        key=lambda p: p.latency_ms,
    )


def pareto_chart(points: list[ParetoPoint], path: Path, title: str) -> None:
    on_front = {p.label for p in front(points)}
    fig, ax = plt.subplots(figsize=(9, 6))
    for p in points:
        bold = p.label.startswith("**")
        colour = (
            "tab:red"
            if "paper" in p.label
            else "tab:green"
            if bold
            else ("tab:blue" if p.label in on_front else "tab:gray")
        )
        ax.scatter(p.latency_ms, p.rmse_nmm, s=60 if bold else 25, color=colour, zorder=3)
        ax.annotate(
            p.label.replace("**", ""),
            (p.latency_ms, p.rmse_nmm),
            fontsize=7,
            xytext=(4, 3),
            textcoords="offset points",
        )
    line = front(points)
    ax.plot(
        [p.latency_ms for p in line],
        [p.rmse_nmm for p in line],
        "b--",
        lw=0.8,
        label="Pareto front",
    )
    ax.set_xscale("log")
    ax.set_xlabel("median latency per frame, one thread (ms, log)")
    ax.set_ylabel("tilt-torque RMSE after calibration (N*mm, mean of tau_x, tau_y)")
    ax.set_title(title, fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
