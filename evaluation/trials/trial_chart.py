"""The PNG summary of one simulated trial: the estimated torques with the phases as bands,
the wrist's true force, and the plug tip's true path over the hole (matplotlib, Agg);
``write_trial_chart`` puts it in the trial's record as ``summary.png``."""

from __future__ import annotations

import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from evaluation.common.outputs import atomic_file  # noqa: E402
from evaluation.trials.result import TrialResult  # noqa: E402

CHART_NAME = "summary.png"

PHASE_COLOURS = {
    "grasp": "#dddddd", "approach": "#cfe2f3", "search": "#fff2cc", "align": "#d9ead3",
    "insert": "#b6d7a8", "backoff": "#f4cccc", "release": "#e6e0f8", "retract": "#eeeeee",
    "teleop": "#ffe599", "estop": "#ea9999",
}  # fmt: skip


def _phase_spans(ticks: list[dict]) -> list[tuple[float, float, str]]:
    spans: list[tuple[float, float, str]] = []
    for tick in ticks:
        t, phase = tick["t_s"], tick["phase"]
        if spans and spans[-1][2] == phase:
            spans[-1] = (spans[-1][0], t, phase)
        else:
            spans.append((t, t, phase))
    return spans


def trial_chart(folder: Path, path: Path, title: str) -> None:
    """Draw the trial recorded in ``folder`` (ticks.jsonl, truth.npz) to ``path``."""
    ticks = [json.loads(line) for line in (folder / "ticks.jsonl").read_text().splitlines()]
    truth = np.load(folder / "truth.npz")
    fig, axes = plt.subplots(3, 1, figsize=(9, 9), constrained_layout=True)
    torque_ax, force_ax, path_ax = axes
    for ax in (torque_ax, force_ax):
        for start, end, phase in _phase_spans(ticks):
            ax.axvspan(start, end, color=PHASE_COLOURS.get(phase, "white"), lw=0)
            ax.text(
                (start + end) / 2,
                1.0,
                phase,
                transform=ax.get_xaxis_transform(),
                ha="center",
                va="bottom",
                fontsize=7,
                rotation=30,
            )
    estimated = [tick for tick in ticks if "estimate" in tick]
    t_est = np.array([tick["t_s"] for tick in estimated])
    for key, label in (("tau_x", "tau_x"), ("tau_y", "tau_y"), ("tau_z", "tau_z / 10")):
        scale = 0.1 if key == "tau_z" else 1.0
        values = np.array([tick["estimate"][key] or np.nan for tick in estimated]) * scale
        torque_ax.plot(t_est, values, lw=1, label=label)
    torque_ax.set_ylabel("estimated torque (raw)")
    torque_ax.legend(loc="upper left", fontsize=8)
    t = truth["t_s"]
    force = np.linalg.norm(truth["wrist_wrench_t"][:, :3], axis=1)
    force_ax.plot(t, force, color="k", lw=1, label="|wrist force| (truth)")
    force_ax.plot(
        t,
        truth["contact_force_n"],
        color="tab:red",
        lw=0.6,
        alpha=0.6,
        label="plug contact force (truth)",
    )
    force_ax.set_ylabel("N")
    force_ax.set_xlabel("time (s)")
    force_ax.legend(loc="upper left", fontsize=8)
    hole = np.array([float(truth["hole_x_m"]), float(truth["hole_y_m"])])
    tip = (truth["tip_xyz_b"][:, :2] - hole) * 1e3
    depth = truth["depth_m"] * 1e3
    scatter = path_ax.scatter(tip[:, 0], tip[:, 1], c=depth, s=2, cmap="viridis")
    path_ax.plot(0, 0, "r+", ms=12, label="true hole")
    path_ax.set_aspect("equal")
    path_ax.set_xlabel("tip x - hole x (mm, B)")
    path_ax.set_ylabel("tip y - hole y (mm, B)")
    path_ax.legend(loc="upper left", fontsize=8)
    fig.colorbar(scatter, ax=path_ax, label="tip depth below the surface (mm)")
    fig.suptitle(title)
    with atomic_file(path) as temporary:
        fig.savefig(temporary, dpi=90, format="png")
    plt.close(fig)


def write_trial_chart(folder: Path, result: TrialResult) -> Path:
    """The chart of the trial recorded in ``folder``, titled with its ``result``, as
    ``folder/summary.png``; its path."""
    title = f"{result.task} seed {result.seed} ({result.controller}): " + (
        "inserted" if result.success else f"failed: {result.failure_reason}"
    )
    path = folder / CHART_NAME
    trial_chart(folder, path, title)
    return path
