"""Charts of trial batches (PNG, matplotlib's Agg canvas, written atomically).

* ``speed_success_chart``: success rate against the insertion speed setting, one line per
  controller, the 95% Wilson interval as error bars (the insertion speed/success chart);
* ``time_histogram``: time to insert of the successful trials, one step histogram per
  controller on shared bins.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from evaluation.common.outputs import atomic_file

DPI = 90
DODGE = 0.012  # relative horizontal shift between controllers, so equal points stay visible


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
    points shifted apart by a hair, so that equal ones stay visible)."""
    fig = Figure(figsize=(7.0, 4.5), layout="constrained")
    ax = fig.add_subplot()
    middle = (len(series) - 1) / 2
    for index, (controller, points) in enumerate(series.items()):
        ordered = sorted((s, p) for s, p in points if p.get("n"))
        if not ordered:
            continue
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
    ax.set_xlabel(speed_label)
    ax.set_ylabel("success rate, % (95% Wilson interval)")
    ax.set_ylim(-2, 102)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="lower left")
    ax.set_title(title, fontsize=10)
    _save(fig, path)


def time_histogram(
    times_s: Mapping[str, Sequence[float]], path: Path, title: str, bins: int = 20
) -> None:
    """``times_s``: controller -> times to insert (simulated s) of its successful trials."""
    fig = Figure(figsize=(7.0, 4.5), layout="constrained")
    ax = fig.add_subplot()
    every = np.concatenate([np.asarray(t, dtype=float) for t in times_s.values()] or [[]])
    edges = np.histogram_bin_edges(every if every.size else [0.0, 1.0], bins=bins)
    for controller, times in times_s.items():
        values = np.asarray(times, dtype=float)
        ax.hist(
            values,
            bins=edges,
            histtype="step",
            linewidth=1.5,
            linestyle="--" if controller == "oracle" else "-",
            label=f"{controller_label(controller)} (n={values.size})",
        )
    ax.set_xlabel("time to insert, s (simulated)")
    ax.set_ylabel("trials")
    ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    ax.grid(True, alpha=0.3)
    ax.legend()
    ax.set_title(title, fontsize=10)
    _save(fig, path)
