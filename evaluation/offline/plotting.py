"""Charts of estimate series (matplotlib, Agg backend: no display needed)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from controller.cli.outputs import atomic_file  # noqa: E402


def plot_series_against_truth(
    t_s: Sequence[float],
    panels: Sequence[tuple[str, Sequence[float], Mapping[str, Sequence[float]]]],
    path: Path,
    title: str,
) -> None:
    """One panel per (name, truth, {label: series}) row; writes a PNG to ``path``
    (atomically: an earlier chart stays until the new one is complete)."""
    fig, axes = plt.subplots(len(panels), 1, figsize=(9, 2.2 * len(panels)), sharex=True)
    axes = [axes] if len(panels) == 1 else axes
    for ax, (name, truth, estimates) in zip(axes, panels, strict=True):
        ax.plot(t_s, truth, color="black", lw=2.0, label="applied pattern")
        for label, values in estimates.items():
            ax.plot(t_s, values, lw=1.2, label=label)
        ax.set_ylabel(name)
        ax.grid(alpha=0.3)
        ax.legend(loc="upper right", fontsize=7)
    axes[-1].set_xlabel("time (s)")
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    try:
        with atomic_file(path) as temporary:
            fig.savefig(temporary, dpi=110, format="png")
    finally:
        plt.close(fig)
