"""Which of the scene's per-seed draws a batch's failures share (``python -m evaluation
draw_failures``).

    draw_failures.py OUT [--bins N]

OUT is a batch folder (``run_trials.py --out``: ``batch.json`` and ``trials.csv``) or a
comparison (``compare_trials.py --out``: one batch per ``cells/<controller>/<speed>/``).
Each trial's seed is drawn again exactly as its scene drew it
(``drivers.sim.scenes.insertion.draws.draw_scene``, with the task and the overrides its
``batch.json`` names; no trial runs), and every batch gets a table: for each drawn quantity,
its range cut into N equal bins, and the failed trials over the trials in each bin. It reads
the simulator's truth after the trials, which no controller sees; it writes nothing.

The quantities (all about the nominal the machine knows; mm and degrees):

* ``hole yaw deg (abs)``: the opening's yaw off nominal, about B z;
* ``hole offset mm``: the opening's horizontal distance from nominal, in B;
* ``board height mm``: the board surface above nominal (the opening moves with it);
* ``board tilt deg (abs)``: the larger of the board's two tilts;
* ``grasp tilt x deg (abs)``, ``grasp tilt z deg (abs)``: the plug turned in the fingers about x_S
  (its width) and z_S (the gel's normal);
* ``grasp tilt x deg``: the first with its sign (positive turns the plug's axis, y_S, toward
  z_S), since the approach leans the plug about the same axis and a tilt adds to the lean
  or takes from it;
* ``grasp along mm``, ``grasp across mm``: the plug moved in the fingers along its axis
  (positive: toward its tip) and across it, along x_S;
* ``reach shortfall mm``: ``-(grasp along + board height)``, how much deeper than nominal the
  arm must go for the tip to reach the depth (a position-only push falls short by it).

Bad input (no batch, a batch of another version, an unknown task): one line, exit 2.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from controller.cli.support import ToolError, integer, run_tool
from controller.run.task import load_task
from core.subcommands import job_prog
from core.task_geometry import HolePose
from drivers.sim.scenes.insertion.draws import SceneDraw, draw_scene
from evaluation.trials.batch import CSV_NAME, PLAN_NAME, read_batch
from evaluation.trials.compare import CELLS

Quantity = Callable[[SceneDraw, HolePose], float]

QUANTITIES: dict[str, Quantity] = {
    "hole yaw deg (abs)": lambda d, n: abs(math.degrees(d.hole.yaw_rad - n.yaw_rad)),
    "hole offset mm": lambda d, n: 1e3 * math.hypot(d.hole.x_m - n.x_m, d.hole.y_m - n.y_m),
    "board height mm": lambda d, n: 1e3 * (d.hole.z_m - n.z_m),
    "board tilt deg (abs)": lambda d, n: max(abs(math.degrees(t)) for t in d.board_tilt_rad),
    "grasp tilt x deg (abs)": lambda d, n: abs(math.degrees(d.grasp.tilt_x_rad)),
    "grasp tilt x deg": lambda d, n: math.degrees(d.grasp.tilt_x_rad),
    "grasp tilt z deg (abs)": lambda d, n: abs(math.degrees(d.grasp.tilt_z_rad)),
    "grasp along mm": lambda d, n: 1e3 * d.grasp.along_m,
    "grasp across mm": lambda d, n: 1e3 * d.grasp.across_m,
    "reach shortfall mm": lambda d, n: -1e3 * (d.grasp.along_m + d.hole.z_m - n.z_m),
}


@dataclass(frozen=True)
class BinCount:
    """One bin of a quantity: its range [``low``, ``high``] and its trials."""

    low: float
    high: float
    failed: int
    trials: int


def binned(values: Sequence[float], failed: Sequence[bool], bins: int) -> list[BinCount]:
    """``values`` cut into ``bins`` equal bins over their range (the top edge included in
    the last), with the failed trials and the trials in each."""
    edges = np.linspace(min(values), max(values), bins + 1)
    index = np.clip(np.searchsorted(edges, values, side="right") - 1, 0, bins - 1)
    counts = []
    for b in range(bins):
        members = index == b
        counts.append(
            BinCount(
                float(edges[b]),
                float(edges[b + 1]),
                int(np.sum(np.asarray(failed)[members])),
                int(np.sum(members)),
            )
        )
    return counts


def batch_folders(out: Path) -> list[Path]:
    """The batch folders in ``out``: itself, or its comparison's cells."""
    if (out / PLAN_NAME).is_file():
        return [out]
    cells = sorted(p.parent for p in (out / CELLS).glob(f"*/*/{PLAN_NAME}"))
    if not cells:
        raise ToolError(
            f"'{out}' holds no {PLAN_NAME} nor {CELLS}/<controller>/<speed>/{PLAN_NAME}; "
            "expected a run_trials or compare_trials output folder"
        )
    return cells


def batch_table(folder: Path, bins: int) -> list[str]:
    """The markdown section of one batch folder (see the module doc)."""
    plan, results = read_batch(folder)
    if not results:
        raise ToolError(f"'{folder / CSV_NAME}': no finished trial in it")
    task = load_task(plan["task"], tuple(plan.get("overrides", ())), with_calibration=False)
    nominal = task.config.hole
    draws = [draw_scene(nominal, task.scene, r.seed) for r in results]
    failed = [not r.success for r in results]
    title = f"### {plan['task']}, `{plan.get('controller', '?')}`"
    if "speed" in plan:
        title += f" at {plan.get('speed_key', 'speed')}={plan['speed']:g}"
    lines = [
        title,
        "",
        f"{sum(failed)} of {len(results)} trials failed (seeds {plan.get('seeds', '?')}); "
        "each cell: failed / trials in the bin.",
        "",
        "| drawn quantity | " + " | ".join(f"bin {b + 1}" for b in range(bins)) + " |",
        "|---|" + "---|" * bins,
    ]
    for name, quantity in QUANTITIES.items():
        values = [quantity(d, nominal) for d in draws]
        cells = [
            f"{c.low:+.2f}..{c.high:+.2f}: {c.failed}/{c.trials}"
            for c in binned(values, failed, bins)
        ]
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return lines


def report(out: Path, bins: int) -> str:
    """Every batch's table in ``out``, as markdown."""
    sections = [batch_table(folder, bins) for folder in batch_folders(out)]
    return "\n\n".join("\n".join(lines) for lines in sections) + "\n"


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog=job_prog("draw_failures"), description=__doc__.splitlines()[0]
    )
    parser.add_argument("out", type=Path, help="a run_trials or compare_trials output folder")
    parser.add_argument("--bins", type=integer(1, 20), default=4, help="bins per quantity")
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)

    def body() -> int:
        if not args.out.is_dir():
            raise ToolError(f"'{args.out}' is not a folder; expected a batch's output folder")
        print(report(args.out, args.bins), end="")
        return 0

    return run_tool("draw_failures", body)
