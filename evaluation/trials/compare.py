"""Controllers compared side by side on the same seeds, across insertion speed settings.

    tactile compare --task usb_c --seeds 0:200 --out out/compare/usb_c
        [--controllers dipole,fingervision,zero_torque,torque_only,align,blind,oracle]
        [--speeds 0.002,0.004,0.008]
        [--speed-key machine.insert.speed_m_s] [--workers N] [--executor local|ray]
        [--ray-address ADDR] [--set KEY=VALUE ...] [--resume]

Every controller runs every speed setting (``--set SPEED_KEY=value`` added to the trials'
overrides) on the same seeds; all the trials share one executor. OUT gets:

* ``cells/<controller>/<speed>/{trials.csv,summary.json}``: one batch per grid cell;
* ``speed_success.png``: success rate (95% Wilson interval) against the speed setting per
  controller -- the insertion speed/success chart (with one speed: per controller);
* ``time_to_insert_<speed>.png``: success against time to insert (the share of trials
  inserted within t, against t) per controller, one chart per speed setting;
* ``grasp_errors_<controller>_<speed>.png``: the histograms of the in-hand estimate's
  signed errors, one per quantity estimated (FEEL, evaluation/trials/grasp_scores.py), for
  each cell whose controller has one;
* ``comparison.md``: the table, the product's targets judged at each speed
  (evaluation/trials/targets.py) and the charts, as a section for docs/EVALUATION.md;
  ``comparison.json``: every cell's summary.

The oracle controller reads the simulator's true wrench with the sensor's measured noise (a
reference, labelled so; evaluation/trials/oracle.py says why it is not an upper bound by
construction).
Ctrl-C or SIGTERM stops the grid; what finished is still summarised and charted (exit 130
or 143). ``--resume`` continues a grid stopped before its end (any way, a kill included)
with the same arguments: each cell keeps its finished trials (evaluation/trials/batch.py).
Bad arguments: one line ``compare_trials: error: ...`` and exit code 2.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from controller.cli.outputs import write_text
from controller.cli.support import ToolError, distinct, number_list, run_tool
from core.config import ConfigError, parse_override
from core.subcommands import job_prog
from evaluation.trials.batch import Batch, run_batches
from evaluation.trials.batch_cli import (
    EXIT_CODES,
    add_run_arguments,
    check_batches,
    check_out,
    check_run_arguments,
    executor_context,
    load_trial_function,
    make_executor,
)
from evaluation.trials.charts import (
    controller_label,
    grasp_error_chart,
    speed_success_chart,
    success_time_chart,
)
from evaluation.trials.grasp_scores import TABLE_HEADER, chart_errors, table_cells
from evaluation.trials.oracle import TRIAL_CONTROLLERS
from evaluation.trials.spec import SeedSpecs, format_seeds
from evaluation.trials.targets import targets_markdown

DEFAULT_SPEED_KEY = "machine.insert.speed_m_s"
DEFAULT_SPEEDS = (0.002, 0.004, 0.008)
SPEED_CHART = "speed_success.png"
TABLE = "comparison.md"
SUMMARIES = "comparison.json"
CELLS = "cells"


@dataclass(frozen=True)
class Cell:
    """One point of the grid: a controller at one speed setting."""

    controller: str
    speed: float

    @property
    def folder(self) -> Path:
        return Path(CELLS) / self.controller / f"{self.speed:g}"


def histogram_name(speed: float) -> str:
    return f"time_to_insert_{speed:g}.png"


def grasp_chart_name(cell: Cell) -> str:
    return f"grasp_errors_{cell.controller}_{cell.speed:g}.png"


def _grasp_markdown(cells: Mapping[Cell, Batch]) -> list[str]:
    """The in-hand estimate's errors per cell that has one (evaluation/trials/grasp_scores),
    as a table and its histograms; nothing when no cell has one."""
    rows, charts = [], []
    for cell, batch in cells.items():
        g = batch.summary.get("grasp_estimate")
        if g is None:
            continue
        label = f"| {controller_label(cell.controller)} | {cell.speed:g} | "
        rows += [label + " | ".join(row) + " |" for row in table_cells(g)]
        charts += [f"![in-hand estimate errors, {cell.controller}]({grasp_chart_name(cell)})", ""]
    if not rows:
        return []
    return [
        "",
        "The plug in the hand, found by touch (FEEL) against the scene's truth: the absolute "
        "errors of each quantity estimated (trials with an estimate of it, of all); a quantity "
        "not estimated gives its true size in parentheses, for scale. The histograms show the "
        "signed errors (estimate - truth).",
        "",
        "| controller | speed | " + " | ".join(TABLE_HEADER) + " |",
        "|---|---:|---|---:|---:|---:|---:|",
        *rows,
        "",
        *charts,
    ]


def grid(
    task: str,
    seeds: range,
    controllers: Sequence[str],
    speed_key: str,
    speeds: Sequence[float],
    overrides: Sequence[str],
    out: Path,
    context: Mapping[str, Any],
) -> dict[Cell, Batch]:
    """One batch per (controller, speed), every one on ``seeds``, in ``out/cells/...``."""
    batches = {}
    for controller in controllers:
        for speed in speeds:
            cell = Cell(controller, speed)
            cell_overrides = (*overrides, f"{speed_key}={speed!r}")
            specs = SeedSpecs(task, controller, seeds, cell_overrides)
            cell_context = {
                "task": task,
                "controller": controller,
                "seeds": format_seeds(seeds),
                "overrides": list(cell_overrides),
                "speed_key": speed_key,
                "speed": speed,
                **context,
            }
            batches[cell] = Batch(specs, out / cell.folder, cell_context)
    return batches


def _percent(value: float | None) -> str:
    return "–" if value is None else f"{value:.1%}"


def _seconds(value: float | None) -> str:
    return "–" if value is None else f"{value:.2f}"


def _milli(value: float | None) -> str:
    """N*m as mN*m, or a dash for none."""
    return "–" if value is None else f"{value * 1e3:.1f}"


def comparison_markdown(
    task: str, seeds: str, speed_key: str, cells: Mapping[Cell, Batch], command: str
) -> str:
    """The comparison as a markdown section: table, then the charts (paths relative to
    the markdown file)."""
    lines = [
        f"## Insertion trials: controllers compared ({task})",
        "",
        f"Seeds {seeds} (B excluded), the same for every controller and speed; the speed "
        f"setting is `{speed_key}`. Success rates with their 95% Wilson interval; times are "
        "simulated seconds from the controller's start (after the gripper's activation) to "
        "the depth, over the successful trials; forces are the simulator's truth (largest "
        "peak and largest p99 over the trials): the plug's insertion force (the net contact "
        "force along the hole's axis; a trial above the connector's specified insertion force "
        "fails), its summed normal contact force (a wedge's squeeze counts once per wall) and "
        "the compliant wrist's force; the walls' torques on the plug as it went in are the "
        "medians of the trials' RMS change at the gel from the hold in the air (the tilt "
        "torque's magnitude and the in-plane torque's). Regenerate with:",
        "",
        f"    {command}",
        "",
        f"| controller | {speed_key} | trials | success | 95% CI | median time s | p90 time s "
        "| insertion force max N | insertion force p99 N | over insertion limit "
        "| summed contact force max N | wrist force max N | entry tilt torque mN*m "
        "| entry in-plane torque mN*m | failures |",
        "|---|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|",
    ]
    for cell, batch in cells.items():
        s = batch.summary
        ci = s["success_ci95"]
        failures = ", ".join(f"{k}: {v}" for k, v in s["failures"].items()) or "none"
        lines.append(
            f"| {controller_label(cell.controller)} | {cell.speed:g} | {s['n']} | "
            f"{_percent(s['success_rate'])} | "
            f"{'–' if ci is None else f'{ci[0]:.1%}–{ci[1]:.1%}'} | "
            f"{_seconds(s['median_time_s'])} | {_seconds(s['p90_time_s'])} | "
            f"{_seconds(s['max_insertion_force_n'])} | {_seconds(s['p99_insertion_force_n'])} | "
            f"{s['insertion_force_violation_trials']} | {_seconds(s['max_contact_force_n'])} | "
            f"{_seconds(s['max_wrist_force_n'])} | "
            f"{_milli(s.get('entry_tilt_torque_median_nm'))} | "
            f"{_milli(s.get('entry_inplane_torque_median_nm'))} | "
            f"{failures} |"
        )
    incomplete = sum(not b.summary["complete"] for b in cells.values())
    if incomplete:
        lines += ["", f"**Incomplete:** {incomplete} cells were stopped before all their trials."]
    speeds = sorted({c.speed for c in cells})
    for speed in speeds:
        at_speed = {c.controller: b.summary for c, b in cells.items() if c.speed == speed}
        lines += ["", *targets_markdown(at_speed, f"{speed_key}={speed:g}")]
    lines += ["", f"![success against {speed_key}]({SPEED_CHART})", ""]
    for speed in speeds:
        lines += [
            f"![success against time to insert at {speed_key}={speed:g}]({histogram_name(speed)})",
            "",
        ]
    lines += _grasp_markdown(cells)
    return "\n".join(lines)


def write_comparison(
    out: Path, task: str, seeds: str, speed_key: str, cells: Mapping[Cell, Batch], command: str
) -> None:
    """The charts, ``comparison.md`` and ``comparison.json`` of a finished grid in ``out``."""
    series: dict[str, list[tuple[float, dict[str, Any]]]] = {}
    for cell, batch in cells.items():
        series.setdefault(cell.controller, []).append((cell.speed, batch.summary))
    speeds = sorted({c.speed for c in cells})
    against = "per controller" if len(speeds) == 1 else "against insertion speed"
    speed_success_chart(
        series, out / SPEED_CHART, speed_key, f"{task}: success {against}, seeds {seeds}"
    )
    for speed in speeds:
        at_speed = {c.controller: b for c, b in cells.items() if c.speed == speed}
        times = {
            controller: [
                r.time_to_insert_s
                for r in batch.results
                if r.success and r.time_to_insert_s is not None
            ]
            for controller, batch in at_speed.items()
        }
        success_time_chart(
            times,
            {controller: len(batch.results) for controller, batch in at_speed.items()},
            out / histogram_name(speed),
            f"{task}: success against time to insert at {speed_key}={speed:g}, seeds {seeds}",
        )
    for cell, batch in cells.items():
        errors = chart_errors(batch.results)
        if errors:
            grasp_error_chart(
                errors,
                out / grasp_chart_name(cell),
                f"{task}: the plug in the hand by touch, {cell.controller}, seeds {seeds}",
                len(batch.results),
            )
    write_text(out / TABLE, comparison_markdown(task, seeds, speed_key, cells, command) + "\n")
    every = [
        {"controller": c.controller, "speed": c.speed, "summary": b.summary}
        for c, b in cells.items()
    ]
    write_text(out / SUMMARIES, json.dumps(every, indent=2) + "\n")


# -- command line ------------------------------------------------------------------------------


def _controllers(text: str) -> tuple[str, ...]:
    names = tuple(part.strip() for part in text.split(","))
    for name in names:
        if name not in TRIAL_CONTROLLERS:
            raise argparse.ArgumentTypeError(
                f"expected comma-separated controllers among {', '.join(TRIAL_CONTROLLERS)}, "
                f"got {name!r}"
            )
    return names


def _speed_key(text: str) -> str:
    try:
        key, _ = parse_override(f"{text}=0")
    except ConfigError:
        raise argparse.ArgumentTypeError(
            f"expected a dotted configuration key, got {text!r}"
        ) from None
    return key


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog=job_prog("compare_trials"),
        description="Compare controllers across insertion speed settings on the same seeds.",
    )
    add_run_arguments(parser)
    parser.add_argument(
        "--controllers",
        type=_controllers,
        default=tuple(TRIAL_CONTROLLERS),
        help=f"comma-separated (default {','.join(TRIAL_CONTROLLERS)})",
    )
    parser.add_argument("--speed-key", type=_speed_key, default=DEFAULT_SPEED_KEY)
    parser.add_argument(
        "--speeds",
        type=number_list(0.0, 1e6, "the speed key's unit"),
        default=DEFAULT_SPEEDS,
        help="comma-separated speed settings (default "
        f"{','.join(f'{s:g}' for s in DEFAULT_SPEEDS)})",
    )
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    check_run_arguments(parser, args)
    distinct(parser, "--controllers", list(args.controllers))
    distinct(parser, "--speeds", [f"{s:g}" for s in args.speeds])
    if any(parse_override(item)[0] == args.speed_key for item in args.overrides):
        parser.error(f"argument --set: {args.speed_key} is the speed key; use --speeds")
    return run_tool("compare_trials", lambda: _run(args))


def _command(args: argparse.Namespace) -> str:
    parts = [
        "tactile compare",
        f"--task {args.task}",
        f"--seeds {format_seeds(args.seeds)}",
        f"--controllers {','.join(args.controllers)}",
        f"--speed-key {args.speed_key}",
        f"--speeds {','.join(f'{s:g}' for s in args.speeds)}",
        *(f"--set {item}" for item in args.overrides),
        f"--workers {args.workers}",
        f"--out {args.out}",
    ]
    return " ".join(parts)


def _run(args: argparse.Namespace) -> int:
    if not args.resume and (args.out / CELLS).is_dir():
        raise ToolError(
            f"--out '{args.out}' already holds a comparison ({CELLS}/); choose a new folder "
            "(or remove it first, or continue it with --resume)"
        )
    check_out(args)
    cells = grid(
        args.task,
        args.seeds,
        args.controllers,
        args.speed_key,
        args.speeds,
        args.overrides,
        args.out,
        executor_context(args),
    )
    function, check = load_trial_function(args.trial_function)
    check_batches(check, list(cells.values()))
    stopped = run_batches(function, list(cells.values()), make_executor(args), resume=args.resume)
    seeds = format_seeds(args.seeds)
    write_comparison(args.out, args.task, seeds, args.speed_key, cells, _command(args))
    print((args.out / TABLE).read_text())
    if stopped is not None:
        print(
            f"compare_trials: interrupted by {stopped}; the comparison in {args.out} holds "
            "the trials that finished",
            file=sys.stderr,
        )
        return EXIT_CODES[stopped]
    return 0
