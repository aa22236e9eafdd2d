"""Success against time to insert, charted from finished batch folders
(``python -m evaluation success_chart``).

    python -m evaluation success_chart DIR[=LABEL] [DIR[=LABEL] ...] --out CHART.png \\
        [--seeds A:B] [--title TEXT]

Each DIR is a batch folder (``tactile trials --out``: its ``trials.csv``, read as
``evaluation.trials.batch.read_trials`` reads it); LABEL names its curve (default: the
batch's controller). ``--seeds A:B`` keeps the trials of those seeds, and each batch must
hold every one of them, so the curves compare the same seeds; without it, every batch must
hold the same seeds. The chart is ``evaluation.trials.charts.success_time_chart``: for each
batch, the share of its trials (failures included) inserted within t, against t (simulated
s). The inputs are only read. Bad input (a DIR without a ``trials.csv``, two curves of one
label, a seed missing from a batch, an output inside an input): one line, exit 2.
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path

from controller.cli.outputs import check_output_file
from controller.cli.support import ToolError, run_tool
from controller.run.result import TrialResult
from core.subcommands import job_prog
from evaluation.trials.batch import CSV_NAME, read_trials
from evaluation.trials.batch_cli import seeds_type
from evaluation.trials.charts import success_time_chart
from evaluation.trials.spec import format_seeds

PROG = "success_chart"


@dataclass(frozen=True)
class Curve:
    """One batch's curve: its ``label`` and its ``results`` (of the chart's seeds)."""

    label: str
    results: list[TrialResult]


def curve_argument(text: str) -> tuple[Path, str | None]:
    """``DIR[=LABEL]`` -> (DIR, LABEL or None)."""
    folder, _, label = text.partition("=")
    return Path(folder), label.strip() or None


def read_curve(folder: Path, label: str | None, seeds: range | None) -> Curve:
    """``folder``'s batch as a curve of ``seeds`` (all its trials without); ToolError naming
    the folder if it holds no table or lacks a seed."""
    results = read_trials(folder)
    if seeds is not None:
        results = [r for r in results if r.seed in seeds]
        missing = sorted(set(seeds) - {r.seed for r in results})
        if missing:
            raise ToolError(f"'{folder / CSV_NAME}': no trial of seed {missing[0]} (--seeds "
                            f"{format_seeds(seeds)}: every batch needs every seed)")  # fmt: skip
    name = label or ", ".join(sorted({r.controller for r in results}))
    return Curve(name, results)


def check_same_seeds(curves: list[Curve]) -> None:
    """ToolError unless every curve holds the same seeds, once each."""
    first = sorted(r.seed for r in curves[0].results)
    for curve in curves:
        seeds = sorted(r.seed for r in curve.results)
        if seeds != first:
            raise ToolError(f"'{curve.label}' holds other seeds than '{curves[0].label}'; "
                            "give --seeds A:B, held by every batch")  # fmt: skip


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog=job_prog(PROG), description=__doc__.splitlines()[0])
    parser.add_argument("curves", type=curve_argument, nargs="+", metavar="DIR[=LABEL]",
                        help="a batch folder and, after =, its curve's label")  # fmt: skip
    parser.add_argument("--out", type=Path, required=True, help="the chart's PNG file")
    parser.add_argument("--seeds", type=seeds_type, default=None,
                        help="A:B, the seeds A up to B (B excluded) of every batch")  # fmt: skip
    parser.add_argument("--title", default=None, help="the chart's title")
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)

    def body() -> int:
        check_output_file(args.out, [folder for folder, _ in args.curves])
        curves = [read_curve(folder, label, args.seeds) for folder, label in args.curves]
        labels = [c.label for c in curves]
        if len(set(labels)) != len(labels):
            twice = sorted({n for n in labels if labels.count(n) > 1})
            raise ToolError(f"two curves are labelled {', '.join(twice)}; give DIR=LABEL")
        check_same_seeds(curves)
        seeds = sorted(r.seed for r in curves[0].results)
        title = args.title or f"inserted within t, seeds {seeds[0]}..{seeds[-1]}"
        times = {c.label: [r.time_to_insert_s for r in c.results
                           if r.success and r.time_to_insert_s is not None]
                 for c in curves}  # fmt: skip
        success_time_chart(times, {c.label: len(c.results) for c in curves}, args.out, title)
        for c in curves:
            print(f"{c.label}: {len(times[c.label])}/{len(c.results)} inserted")
        print(f"wrote {args.out}")
        return 0

    return run_tool(PROG, body)
