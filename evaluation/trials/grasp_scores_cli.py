"""FEEL's in-hand estimate scored on finished batches (``python -m evaluation grasp_scores``).

    python -m evaluation grasp_scores DIR [DIR ...] --out OUT_DIR

Each DIR is a batch folder (``tactile trials --out``: its ``trials.csv``; ``batch.json``, if
there, names the seeds); no trial runs. The scores are evaluation/trials/grasp_scores.py's,
as a batch's ``summary.json`` and ``tactile compare`` give them: for each quantity some
trial estimates (the tilts about T x and T y, each against the hand and against the
receptacle's axis; the tip's offsets along T y and T x; the plug's offset across the
fingers), the absolute error's median, 95th percentile and largest over the trials with an
estimate of it; a quantity no trial estimates is "not estimated" (its true size, for scale).
OUT_DIR gets:

* ``grasp_scores.md``: the table, one row per batch and quantity, a note per batch and plane
  on the board's share of its errors (``grasp_scores.board_share``: FEEL reads the plug
  against the receptacle's axis, the board's tilt away from the hand's), and the charts;
* ``grasp_errors_<DIR's name>.png``: per batch with an estimate, a histogram of the signed
  error (estimate - truth) of each quantity it estimates;
* ``grasp_scores.json``: each batch's block (the summary's ``grasp_estimate``; null without
  an estimate) and its ``board_share`` per plane (``thickness``, ``width``: null below 3
  trials with both truths).

A ``trials.csv`` written before a pose column existed reads it as unknown. One from before
``tip_y_est_m`` gets it from the thickness-plane tilt as the machine computes it
(``controller.insertion.grasp_estimate.tilt_tip_offset_m``, the plug's length from the
batch's task and overrides), and the table says so. The inputs are only read. Bad input (a
DIR without a ``trials.csv``, a table of another kind, an output inside an input): one line,
exit 2.
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from controller.cli.outputs import check_output_folder, write_text
from controller.cli.support import ToolError, run_tool
from controller.insertion.grasp_estimate import tilt_tip_offset_m
from controller.run.result import TrialResult
from controller.run.task import load_task
from core.subcommands import job_prog
from evaluation.trials.batch import CSV_NAME, PLAN_NAME, read_trials
from evaluation.trials.charts import grasp_error_chart
from evaluation.trials.grasp_scores import (
    PLANES,
    TABLE_HEADER,
    Plane,
    board_shares,
    chart_errors,
    grasp_estimate_summary,
    table_cells,
)

PROG = "grasp_scores"
TABLE = "grasp_scores.md"
BLOCKS = "grasp_scores.json"
DERIVED = "tip_y_est_m"  # the column an older table lacks and this tool derives


@dataclass(frozen=True)
class Scored:
    """One batch: its folder, ``name`` (the folder's), ``title`` (task, controller, seeds),
    its results, the plug's length from the TCP to the tip (m, the batch's task and
    overrides) and whether ``tip_y_est_m`` was derived (an older table)."""

    folder: Path
    name: str
    title: str
    results: list[TrialResult]
    length_m: float
    derived: bool


def read_results(folder: Path) -> tuple[list[TrialResult], bool]:
    """The results of ``folder``'s ``trials.csv`` (``evaluation.trials.batch.read_table``)
    and whether it has the ``tip_y_est_m`` column; ToolError naming the file if it is
    missing, not a trials table, or has a bad row or none."""
    results = read_trials(folder)
    with (folder / CSV_NAME).open(newline="") as handle:
        has_tip_y = DERIVED in next(csv.reader(handle), [])
    return results, has_tip_y


def _plan(folder: Path) -> dict[str, Any]:
    try:
        plan = json.loads((folder / PLAN_NAME).read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError):
        return {}
    return plan if isinstance(plan, dict) else {}


def _with_tip_y(results: list[TrialResult], length_m: float) -> list[TrialResult]:
    """``results`` with ``tip_y_est_m`` from the thickness-plane tilt (where estimated) for a
    plug ``length_m`` long."""
    return [
        dataclasses.replace(r, tip_y_est_m=tilt_tip_offset_m(t, length_m))
        if math.isfinite(t := r.grasp_tilt_thickness_est_rad)
        else r
        for r in results
    ]


def score(folder: Path) -> Scored:
    """``folder``'s batch read (ToolError if it cannot be)."""
    if not folder.is_dir():
        raise ToolError(f"'{folder}' is not a folder; expected a batch's folder")
    results, has_tip_y = read_results(folder)
    plan = _plan(folder)
    tasks = {r.task for r in results}
    task = plan.get("task") if isinstance(plan.get("task"), str) else min(tasks)
    controllers = ", ".join(sorted({r.controller for r in results}))
    seeds = plan.get("seeds") or f"{min(r.seed for r in results)}..{max(r.seed for r in results)}"
    overrides = tuple(str(o) for o in plan.get("overrides", ()) or ())
    length = load_task(str(task), overrides, with_calibration=False).config.plug.length_m
    if not has_tip_y:
        results = _with_tip_y(results, length)
    title = f"{', '.join(sorted(tasks))}, {controllers}, seeds {seeds}"
    return Scored(folder, folder.resolve().name, title, results, length, not has_tip_y)


def chart_name(batch: Scored) -> str:
    return f"grasp_errors_{batch.name}.png"


def markdown(
    batches: list[Scored],
    blocks: list[dict[str, Any] | None],
    shares: list[dict[str, Any]],
) -> str:
    """The table of every batch's scores, the notes (``shares``: each batch's ``board_shares``)
    and the charts."""
    lines = [
        "## The plug in the hand by touch (FEEL) against the scene's truth",
        "",
        "Absolute errors of each quantity estimated (trials with an estimate of it, of all); a "
        "quantity not estimated gives its true size in parentheses, for scale. The histograms "
        "show the signed errors (estimate - truth).",
        "",
        "| batch | " + " | ".join(TABLE_HEADER) + " |",
        "|---|---|---:|---:|---:|---:|",
    ]
    notes, charts = [], []
    for batch, block, share_of in zip(batches, blocks, shares, strict=True):
        label = f"{batch.title} (`{batch.name}`)"
        if block is None:
            lines.append(f"| {label} | every quantity | no estimate of {len(batch.results)} | "
                         "– | – | – |")  # fmt: skip
            continue
        lines += [f"| {label} | " + " | ".join(row) + " |" for row in table_cells(block)]
        charts += [f"![in-hand estimate errors, {batch.name}]({chart_name(batch)})", ""]
        if batch.derived and "tip_y_mm" in block["errors"]:
            notes.append(
                f"- `{batch.name}`: its trials.csv has no `{DERIVED}` (written before it "
                "existed); the tip's offset along T y is derived from "
                "`grasp_tilt_thickness_est_rad` as the machine computes it, L sin(tilt) with "
                f"L = {1e3 * batch.length_m:g} mm (the task's plug length)."
            )
        for plane in PLANES:
            if (share := share_of[plane.name]) is not None:
                notes.append(board_note(batch, plane, share))
    return "\n".join([*lines, "", *notes, *([""] if notes else []), *charts]).rstrip() + "\n"


def board_note(batch: Scored, plane: Plane, share: dict[str, float]) -> str:
    """The markdown note on the board's share of ``batch``'s errors in ``plane``."""
    return (
        f"- `{batch.name}`: the board's tilt about {plane.about} (the plug's tilt from the "
        f"receptacle's axis less its tilt in the hand), {share['n']} trials: median "
        f"{share['board_tilt_median_deg']:.2f} deg; the tilt's error follows it (correlation "
        f"{share['correlation']:.2f}); the tip's error along {plane.along} less the board's share, "
        f"L (sin(a + b) - sin a) with L = {1e3 * batch.length_m:g} mm: median "
        f"{share['tip_error_less_board_median_mm']:.2f} mm."
    )


def write(batches: list[Scored], out: Path) -> list[dict[str, Any] | None]:
    """The table, the charts and the blocks of ``batches`` into ``out``; the blocks."""
    blocks = [grasp_estimate_summary(b.results) for b in batches]
    out.mkdir(parents=True, exist_ok=True)
    for batch, block in zip(batches, blocks, strict=True):
        if block is not None:
            grasp_error_chart(
                chart_errors(batch.results),
                out / chart_name(batch),
                f"the plug in the hand by touch: {batch.title}",
                len(batch.results),
            )
    shares = [board_shares(b.results, b.length_m) for b in batches]
    every = {
        b.name: {"folder": str(b.folder), "grasp_estimate": blk, "board_share": share}
        for b, blk, share in zip(batches, blocks, shares, strict=True)
    }
    write_text(out / BLOCKS, json.dumps(every, indent=2) + "\n")
    write_text(out / TABLE, markdown(batches, blocks, shares))
    return blocks


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog=job_prog(PROG), description=__doc__.splitlines()[0])
    parser.add_argument("dirs", type=Path, nargs="+", metavar="DIR",
                        help="a batch folder (its trials.csv)")  # fmt: skip
    parser.add_argument("--out", type=Path, required=True,
                        help="the folder for the table, the charts and the blocks")  # fmt: skip
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)

    def body() -> int:
        check_output_folder(args.out, args.dirs, "--out")
        batches = [score(folder) for folder in args.dirs]
        names = [b.name for b in batches]
        if len(set(names)) != len(names):
            twice = sorted({n for n in names if names.count(n) > 1})
            raise ToolError(f"two batch folders are named {', '.join(twice)}; rename one")
        write(batches, args.out)
        print((args.out / TABLE).read_text(), end="")
        return 0

    return run_tool(PROG, body)
