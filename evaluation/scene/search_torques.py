"""The true gel torques while the machine searches, against the compliant wrist's tilt
stiffness: the sweep that brackets the wrist (docs/SIMULATION.md, "The compliant wrist").

For each ``scene.wrist.tilt_stiffness_nm_rad`` value and each seed, one trial of the task
with the controller (the product's run path, as ``tactile trial`` runs it); from the
scene's truth, the sensing gel's true torques (tau_x, tau_y, tau_z of ``gel_wrench_s``,
N*mm) over the SEARCH phase(s), each relative to its value when SEARCH began (what the
machine's zeroed estimate can see), and the wrist's deflection at the plug's tip. Printed
as a Markdown table: per stiffness, the median over seeds of each torque's p95 and of the
tip's largest lateral deflection, the outcome counts, and the lateral stiffness at the tip
(tilt stiffness / lever^2, lever: pivot to tip).

    python -m evaluation search_torques [--task usb_c] [--seeds 0:5]
        [--stiffness 0.5,5,15,45] [--controller align]
"""

from __future__ import annotations

import argparse
from collections import Counter

import numpy as np

from controller.cli.support import number_list, run_tool
from controller.insertion import Phase
from controller.run import load_task
from evaluation.trials.spec import parse_seeds
from evaluation.trials.trial import run

TASKS = ("usb_c", "usb_a")


def search_windows(transitions, end_s: float) -> list[tuple[float, float]]:
    """(start, end) s of every stretch the machine spent in SEARCH."""
    windows, start = [], None
    for change in transitions:
        if change.target == Phase.SEARCH and start is None:
            start = change.t_s
        elif change.source == Phase.SEARCH and start is not None:
            windows.append((start, change.t_s))
            start = None
    if start is not None:
        windows.append((start, end_s))
    return windows


def search_torques_nmm(truth: dict[str, np.ndarray], windows) -> np.ndarray:
    """(n, 3) true gel torques in N*mm inside the windows, each window's relative to its
    first row (the zero the machine's estimate has when the search starts)."""
    t, tau = truth["t_s"], truth["gel_wrench_s"][:, 3:] * 1e3
    parts = []
    for start, end in windows:
        inside = (t >= start) & (t <= end)
        if inside.any():
            parts.append(tau[inside] - tau[inside][0])
    return np.concatenate(parts) if parts else np.zeros((0, 3))


def sweep(task_name: str, seeds: range, stiffnesses: list[float], controller: str) -> str:
    """The Markdown table of the module docstring."""
    rows = [
        "| tilt stiffness N*m/rad | lateral at the tip N/m | trials | outcomes "
        "| p95 tau_x | p95 tau_y | p95 tau_z (N*mm, medians over seeds) |",
        "|---|---|---|---|---|---|---|",
    ]
    for k in stiffnesses:
        task = load_task(task_name, [f"scene.wrist.tilt_stiffness_nm_rad={k}"])
        lever = task.scene.wrist.pivot_above_tcp_m + task.config.plug.length_m
        p95, outcomes = [], Counter()
        for seed in seeds:
            outcome = run(task, controller, seed)
            truth = outcome.truth
            windows = search_windows(outcome.transitions, float(truth["t_s"][-1]))
            tau = np.abs(search_torques_nmm(truth, windows))
            p95.append(np.percentile(tau, 95, axis=0) if len(tau) else np.full(3, np.nan))
            outcomes[outcome.result.status] += 1
        med = np.nanmedian(np.array(p95), axis=0)
        counts = ", ".join(f"{n} {name}" for name, n in sorted(outcomes.items()))
        rows.append(
            f"| {k:g} | {k / lever**2:.0f} | {len(seeds)} | {counts} | {med[0]:.2f} | "
            f"{med[1]:.2f} | {med[2]:.2f} |"
        )
    return "\n".join(rows)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--task", choices=TASKS, default="usb_c")
    parser.add_argument("--seeds", type=parse_seeds, default=range(0, 5))
    parser.add_argument(
        "--stiffness",
        type=number_list(0.01, 1e4, "N*m/rad"),
        default=(0.5, 5.0, 15.0, 45.0),
        help="tilt stiffnesses, N*m/rad, comma-separated",
    )
    parser.add_argument("--controller", default="align")
    args = parser.parse_args(argv)

    def body() -> int:
        print(sweep(args.task, args.seeds, list(args.stiffness), args.controller))
        return 0

    return run_tool("search_torques", body)
