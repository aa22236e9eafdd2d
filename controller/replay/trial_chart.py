"""The PNG summary of one run: the estimated torques (N*mm when calibrated) and the
commands with the phases as bands, and, in simulation, the plug's true contact force with its
limit beside the wrist's true force, and the plug tip's true path over the hole (matplotlib,
Agg).

``draw_trial_chart(series, path, title)`` draws a ``TrialSeries`` (plain arrays); a trial's
record (``trial_series(folder)``: ticks.jsonl, truth.npz) and an episode file
(controller/replay/episode_chart.py) both give one, so both charts are the same chart.
``write_trial_chart`` puts a trial's in its record as ``summary.png``.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from controller.cli.outputs import atomic_file
from controller.run.result import TrialResult

CHART_NAME = "summary.png"

PHASE_COLOURS = {
    "grasp": "#dddddd", "approach": "#cfe2f3", "feel": "#d0e0e3", "search": "#fff2cc",
    "align": "#d9ead3",
    "insert": "#b6d7a8", "backoff": "#f4cccc", "release": "#e6e0f8", "retract": "#eeeeee",
    "teleop": "#ffe599", "estop": "#ea9999",
}  # fmt: skip
TORQUES = ("tau_x", "tau_y", "tau_z")


@dataclass(frozen=True)
class ChartTruth:
    """The simulator's truth for the chart, one row per truth sample: ``t_s`` (n,),
    ``wrist_wrench_t`` (n, 6: N, N*m), ``contact_force_n`` (n,: summed normal force, N),
    ``insertion_force_n`` (n,: along the hole's axis, N), ``tip_xyz_b`` (n, 3: m, B),
    ``depth_m`` (n,: tip below the surface) and the true hole's ``hole_xy_m`` (2: m, B)."""

    t_s: np.ndarray
    wrist_wrench_t: np.ndarray
    contact_force_n: np.ndarray
    insertion_force_n: np.ndarray
    tip_xyz_b: np.ndarray
    depth_m: np.ndarray
    hole_xy_m: np.ndarray


@dataclass(frozen=True)
class TrialSeries:
    """What the chart draws, s on the loop's clock: each tick's time and the ``phases``
    after its step; the raw estimates' times and ``torques`` (n, 3: tau_x, tau_y, tau_z; NaN
    where none); the commands' times and ``twists`` (n, 6: linear m/s, angular rad/s in B;
    NaN where no twist was sent); the ``truth`` (None on hardware); ``calibrated``: the
    torques are N*m (else the estimator's raw units)."""

    tick_t_s: np.ndarray
    phases: Sequence[str]
    estimate_t_s: np.ndarray
    torques: np.ndarray
    command_t_s: np.ndarray
    twists: np.ndarray
    truth: ChartTruth | None
    calibrated: bool = False


def phase_spans(t_s: np.ndarray, phases: Sequence[str]) -> list[tuple[float, float, str]]:
    """(start s, end s, phase) of each run of equal phases."""
    spans: list[tuple[float, float, str]] = []
    for t, phase in zip(t_s, phases, strict=True):
        if spans and spans[-1][2] == phase:
            spans[-1] = (spans[-1][0], float(t), phase)
        else:
            spans.append((float(t), float(t), phase))
    return spans


def _bands(ax: Axes, spans: list[tuple[float, float, str]], labels: bool) -> None:
    for start, end, phase in spans:
        ax.axvspan(start, end, color=PHASE_COLOURS.get(phase, "white"), lw=0)
        if labels:
            ax.text((start + end) / 2, 1.0, phase, transform=ax.get_xaxis_transform(),
                    ha="center", va="bottom", fontsize=7, rotation=30)  # fmt: skip


def draw_trial_chart(
    series: TrialSeries, path: Path, title: str, contact_force_limit_n: float | None = None
) -> None:
    """Draw ``series`` to the PNG ``path`` (atomically), titled ``title``: torques and
    commands over the phase bands, then, with the truth, the forces (with the plug's
    ``contact_force_limit_n``, N, as a line when given) and the tip's path."""
    truth = series.truth
    panels = 4 if truth is not None else 2
    fig = Figure(figsize=(9, 2.6 * panels + 1), layout="constrained")
    axes = fig.subplots(panels, 1)
    spans = phase_spans(series.tick_t_s, series.phases)
    time_axes = axes[:3] if truth is not None else axes
    for index, ax in enumerate(time_axes):
        _bands(ax, spans, labels=index == 0)
        if index:
            ax.sharex(time_axes[0])
    torque_ax, command_ax = axes[0], axes[1]
    for column, key in enumerate(TORQUES):
        raw_tau_z = key == "tau_z" and not series.calibrated
        scale = 1e3 if series.calibrated else (0.1 if raw_tau_z else 1.0)
        label = "tau_z / 10" if raw_tau_z else key
        torque_ax.plot(series.estimate_t_s, series.torques[:, column] * scale, lw=1, label=label)
    unit = "N*mm" if series.calibrated else "raw"
    torque_ax.set_ylabel(f"estimated torque ({unit})")
    torque_ax.legend(loc="upper left", fontsize=8)
    for column, axis in enumerate("xyz"):
        command_ax.plot(series.command_t_s, series.twists[:, column] * 1e3, lw=1,
                        label=f"v_{axis} (mm/s)")  # fmt: skip
    for column, axis in enumerate("xyz"):
        command_ax.plot(series.command_t_s, np.degrees(series.twists[:, 3 + column]), lw=0.8,
                        ls="--", label=f"w_{axis} (deg/s)")  # fmt: skip
    command_ax.set_ylabel("command (TCP twist, B)")
    command_ax.legend(loc="upper left", fontsize=7, ncol=2)
    if truth is None:
        command_ax.set_xlabel("time (s)")
    else:
        _truth_panels(fig, axes[2], axes[3], truth, contact_force_limit_n)
    fig.suptitle(title)
    with atomic_file(path) as temporary:
        fig.savefig(temporary, dpi=90, format="png")


def _truth_panels(
    fig: Figure,
    force_ax: Axes,
    path_ax: Axes,
    truth: ChartTruth,
    contact_force_limit_n: float | None,
) -> None:
    force = np.linalg.norm(truth.wrist_wrench_t[:, :3], axis=1)
    force_ax.plot(truth.t_s, force, color="k", lw=1, label="|wrist force| (truth)")
    force_ax.plot(truth.t_s, truth.contact_force_n, color="tab:orange", lw=0.6, alpha=0.6,
                  label="plug's summed contact force (truth)")  # fmt: skip
    force_ax.plot(truth.t_s, truth.insertion_force_n, color="tab:red", lw=0.8,
                  label="plug's insertion force (truth)")  # fmt: skip
    if contact_force_limit_n is not None and np.isfinite(contact_force_limit_n):
        force_ax.axhline(contact_force_limit_n, color="tab:red", ls="--", lw=0.8,
                         label=f"insertion-force limit {contact_force_limit_n:g} N")  # fmt: skip
    force_ax.set_ylabel("N")
    force_ax.set_xlabel("time (s)")
    force_ax.legend(loc="upper left", fontsize=8)
    tip = (truth.tip_xyz_b[:, :2] - truth.hole_xy_m) * 1e3
    scatter = path_ax.scatter(tip[:, 0], tip[:, 1], c=truth.depth_m * 1e3, s=2, cmap="viridis")
    path_ax.plot(0, 0, "r+", ms=12, label="true hole")
    path_ax.set_aspect("equal")
    path_ax.set_xlabel("tip x - hole x (mm, B)")
    path_ax.set_ylabel("tip y - hole y (mm, B)")
    path_ax.legend(loc="upper left", fontsize=8)
    fig.colorbar(scatter, ax=path_ax, label="tip depth below the surface (mm)")


def trial_series(folder: Path) -> TrialSeries:
    """The series of the trial recorded in ``folder`` (ticks.jsonl, and truth.npz if there)."""
    ticks = [json.loads(line) for line in (folder / "ticks.jsonl").read_text().splitlines()]
    estimated = [tick for tick in ticks if "estimate" in tick]
    torques = np.array(
        [
            [np.nan if tick["estimate"][k] is None else tick["estimate"][k] for k in TORQUES]
            for tick in estimated
        ]  # fmt: skip
    ).reshape(-1, 3)
    twists = np.array([tick.get("twist", [np.nan] * 6) for tick in ticks]).reshape(-1, 6)
    truth = None
    if (folder / "truth.npz").is_file():
        arrays = np.load(folder / "truth.npz")
        truth = ChartTruth(
            arrays["t_s"],
            arrays["wrist_wrench_t"],
            arrays["contact_force_n"],
            arrays["insertion_force_n"],
            arrays["tip_xyz_b"],
            arrays["depth_m"],
            np.array([float(arrays["hole_x_m"]), float(arrays["hole_y_m"])]),
        )
    tick_t = np.array([tick["t_s"] for tick in ticks])
    calibrated = bool(estimated) and all(tick.get("calibrated", False) for tick in estimated)
    return TrialSeries(
        tick_t,
        [tick["phase"] for tick in ticks],
        np.array([tick["t_s"] for tick in estimated]),
        torques,
        tick_t,
        twists,
        truth,
        calibrated,
    )


def trial_chart(
    folder: Path, path: Path, title: str, contact_force_limit_n: float | None = None
) -> None:
    """Draw the trial recorded in ``folder`` (ticks.jsonl, truth.npz) to ``path``, with the
    plug's ``contact_force_limit_n`` (N) when given."""
    draw_trial_chart(trial_series(folder), path, title, contact_force_limit_n)


def chart_title(task: object, seed: object, controller: object, ended: str) -> str:
    """``TASK seed N (CONTROLLER): ENDED``."""
    return f"{task} seed {seed} ({controller}): {ended}"


def result_text(success: bool, failure_reason: object) -> str:
    """How a trial ended, in the chart's words."""
    return "inserted" if success else f"failed: {failure_reason}"


def insertion_force_text(max_n: object, p99_n: object) -> str:
    """The title's ``; plug insertion force max X N, p99 Y N`` ("" if not numbers)."""
    try:
        return f"; plug insertion force max {float(max_n):.1f} N, p99 {float(p99_n):.1f} N"  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return ""


def write_trial_chart(folder: Path, result: TrialResult) -> Path:
    """The chart of the trial recorded in ``folder``, titled with its ``result``, as
    ``folder/summary.png``; its path."""
    ended = result_text(result.success, result.failure_reason)
    title = chart_title(result.task, result.seed, result.controller, ended) + insertion_force_text(
        result.max_insertion_force_n, result.p99_insertion_force_n
    )
    path = folder / CHART_NAME
    trial_chart(folder, path, title, result.contact_force_limit_n)
    return path
