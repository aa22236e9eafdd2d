"""Charts of trial batches (PNG, matplotlib's Agg canvas, written atomically).

* ``speed_success_chart``: success rate against the insertion speed setting, one line per
  controller, the 95% Wilson interval as error bars (the insertion speed/success chart); with
  a single speed, one point per controller side by side;
* ``success_time_chart``: the share of trials inserted within a time, against that time,
  one step curve per controller (success against time to insert);
* ``grasp_error_chart``: histograms of FEEL's signed errors on the plug in the hand, one per
  estimated quantity (tilts, tip offsets).
"""

from __future__ import annotations

import textwrap
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from controller.cli.outputs import atomic_file

DPI = 90
DODGE = 0.012  # relative horizontal shift between controllers, so equal points stay visible
TITLE_WIDTH = 75  # characters per title line: a longer title wraps rather than being cut off


def _save(fig: Figure, path: Path) -> None:
    with atomic_file(path) as temporary:
        fig.savefig(temporary, dpi=DPI)


def controller_label(controller: str) -> str:
    """The controller's name in charts and tables; the oracle is marked as the true wrench
    (a reference, not an upper bound by construction: evaluation/trials/oracle.py)."""
    return "oracle (true wrench + sensor noise)" if controller == "oracle" else controller


def speed_success_chart(
    series: Mapping[str, Sequence[tuple[float, Mapping[str, Any]]]],
    path: Path,
    speed_label: str,
    title: str,
) -> None:
    """``series``: controller -> [(speed setting, batch summary)]; each point is the
    summary's ``success_rate`` with its ``success_ci95`` as the error bar (the controllers'
    points shifted apart by a hair, so that equal ones stay visible). When every point is at
    one speed the controllers stand side by side, named on the horizontal axis."""
    fig = Figure(figsize=(7.0, 4.5), layout="constrained")
    ax = fig.add_subplot()
    middle = (len(series) - 1) / 2
    speeds_run = {s for points in series.values() for s, p in points if p.get("n")}
    single = len(speeds_run) == 1
    for index, (controller, points) in enumerate(series.items()):
        ordered = sorted((s, p) for s, p in points if p.get("n"))
        if not ordered:
            continue
        if single:
            speeds = np.full(len(ordered), float(index))
        else:
            speeds = np.array([s for s, _ in ordered]) * (1 + DODGE * (index - middle))
        rates = np.array([p["success_rate"] for _, p in ordered]) * 100
        lows = np.array([p["success_ci95"][0] for _, p in ordered]) * 100
        highs = np.array([p["success_ci95"][1] for _, p in ordered]) * 100
        ax.errorbar(
            speeds,
            rates,
            yerr=[rates - lows, highs - rates],
            marker="o",
            capsize=4,
            linestyle="--" if controller == "oracle" else "-",
            label=controller_label(controller),
        )
    if single:
        ax.set_xticks(range(len(series)))
        ax.set_xticklabels([controller_label(c) for c in series], rotation=20, ha="right")
        ax.set_xlim(-0.5, len(series) - 0.5)
        ax.set_xlabel(f"controller ({speed_label} = {next(iter(speeds_run)):g})")
    else:
        ax.set_xlabel(speed_label)
        ax.legend(loc="lower left")
    ax.set_ylabel("success rate, % (95% Wilson interval)")
    ax.set_ylim(-2, 102)
    ax.grid(True, alpha=0.3)
    ax.set_title(textwrap.fill(title, TITLE_WIDTH), fontsize=10)
    _save(fig, path)


def inserted_within(
    times_s: Sequence[float], trials: int, end_s: float
) -> tuple[np.ndarray, np.ndarray]:
    """The step curve of ``success_time_chart``: times (s, from 0 to ``end_s``) and the
    share (%) of ``trials`` inserted by each, from the successful trials' ``times_s``."""
    values = np.sort(np.asarray(times_s, dtype=float))
    steps = np.concatenate([[0.0], values, [end_s]])
    counts = np.concatenate([[0.0], np.arange(1, values.size + 1), [values.size]])
    return steps, 100.0 * counts / max(trials, 1)


def success_time_chart(
    times_s: Mapping[str, Sequence[float]], trials: Mapping[str, int], path: Path, title: str
) -> None:
    """Success against time to insert: for each controller, the share of its ``trials``
    (every trial, failures included) inserted within t, against t (simulated s), a step
    curve. ``times_s``: controller -> times to insert of its successful trials. A curve
    ends at its success rate; one that rises earlier inserts sooner."""
    fig = Figure(figsize=(9.0, 4.5), layout="constrained")
    ax = fig.add_subplot()
    every = [t for times in times_s.values() for t in times]
    end = max(every, default=1.0) * 1.05
    for controller, times in times_s.items():
        n = trials[controller]
        steps, shares = inserted_within(times, n, end)
        ax.step(
            steps,
            shares,
            where="post",
            linewidth=1.5,
            linestyle="--" if controller == "oracle" else "-",
            label=f"{controller_label(controller)} ({len(times)}/{n})",
        )
    ax.set_xlabel("time to insert, s (simulated)")
    ax.set_ylabel("trials inserted within that time, %")
    ax.set_xlim(0.0, end)
    ax.set_ylim(-2, 102)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)  # beside: hides no curve
    ax.set_title(textwrap.fill(title, TITLE_WIDTH), fontsize=10)
    _save(fig, path)


def grasp_error_chart(
    errors: Mapping[str, Sequence[float]], path: Path, title: str, trials: int | None = None
) -> None:
    """Histograms of FEEL's signed errors, estimate - truth (evaluation/trials/grasp_scores.py):
    one per estimated quantity (``errors``: its axis label, unit included, to the errors of
    the trials that estimate it), side by side, zero marked; ``trials``: how many trials the
    errors are of, for the title."""
    panels = [(label, values) for label, values in errors.items() if len(values)]
    fig = Figure(figsize=(4.5 * max(len(panels), 1), 3.6), layout="constrained")
    axes = fig.subplots(1, max(len(panels), 1), squeeze=False)[0]
    colors = ("#4477aa", "#aa7744", "#66aa55", "#aa4466")
    for i, (ax, (label, values)) in enumerate(zip(axes, panels, strict=False)):
        ax.hist(values, bins=20, color=colors[i % len(colors)])
        ax.axvline(0.0, color="black", linewidth=0.8)
        ax.set_xlabel(f"{label}: estimate - truth")
        if i == 0:
            ax.set_ylabel("trials")
    n = max((len(values) for _, values in panels), default=0)
    of = f" of {trials} trials" if trials is not None else ""
    fig.suptitle(textwrap.fill(f"{title} ({n} estimates{of})", TITLE_WIDTH), fontsize=10)
    _save(fig, path)
