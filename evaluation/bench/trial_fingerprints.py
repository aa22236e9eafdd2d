"""What whole simulated trials decided, one digest per seed, to show that a change (a
speed-up, a refactor) leaves every trial's outcome as it was.

    python -m evaluation trial_fingerprints --task usb_c|usb_a|PATH.yaml --seeds A:B
        [--controller dipole|fingervision|zero_torque|torque_only|align|blind|oracle]
        [--set KEY=VALUE ...] [--out FILE.csv] [--against OTHER.csv]
    python -m evaluation trial_fingerprints --compare BEFORE.csv AFTER.csv

Each seed runs the trial tools' own path (``evaluation.trials.trial.run``, as
``tactile trial`` and the batch tools run it), as fast as possible, in this process,
one after the other, writing nothing but this tool's table. A seed's row holds:

* ``outcome``: a digest of everything the trial decided, the ``TrialResult``'s fields
  except ``wall_time_s``, and the machine's transitions (time, source, target, reason,
  rule), floats exactly (``repr``): two runs of the same code on one seed give the same;
* ``truth``: a digest of the simulated world's truth table (every row, bit for bit): equal
  truths mean the same physics, the same controller commands, the same run;
* the fields behind ``outcome``, readable (status, failure, durations, forces) and the
  transitions as ``t_s source>target reason[rule]`` joined by ``; ``, so that a changed
  digest can be explained from the two tables.

A trial that raises is a row of status ``error`` (its exception in ``failure_reason``, no
transitions, no truth), as the batch tools record it; the next seed runs.

The table goes to stdout as each seed finishes and, with ``--out``, to a CSV file (written
atomically at the end). ``--against OTHER.csv`` compares the rows with an earlier table of
the same task and controller (e.g. from another commit): it prints the seeds whose
``outcome`` or ``truth`` differ, field by field, and the count of identical ones;
``--compare BEFORE.csv AFTER.csv`` does the same for two tables already written (AFTER's
rows against BEFORE's), running no trial. Exit codes
as every tool's (controller/cli/support.py): bad input is one line and exit 2; a
difference against ``OTHER.csv`` is reported, not an error (exit 0).

Like the scene's benchmark it limits OpenMP, OpenBLAS and MKL to one thread before NumPy
loads (``python -m evaluation trial_fingerprints``) and OpenCV to one thread, so that the digests do
not depend on the machine's cores.
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import hashlib
import json
import sys
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from controller.cli.outputs import atomic_text, check_output_file
from controller.cli.support import ToolError, add_override_argument, run_tool
from controller.insertion.interface import Transition
from controller.run.result import TrialResult
from controller.run.task import Task, load_task
from core.subcommands import job_prog
from evaluation.trials.batch_cli import seeds_type
from evaluation.trials.guard import error_result
from evaluation.trials.oracle import TRIAL_CONTROLLERS
from evaluation.trials.spec import TrialSpec
from evaluation.trials.trial import raise_if_interrupted, run

PROG = "trial_fingerprints"
IGNORED = ("wall_time_s",)  # what a trial measures but does not decide
RESULT_FIELDS = tuple(f.name for f in dataclasses.fields(TrialResult) if f.name not in IGNORED)
COLUMNS = ("task", "controller", "seed", "outcome", "truth", "transitions") + tuple(
    name for name in RESULT_FIELDS if name not in ("task", "controller", "seed")
)
KEY = ("task", "controller", "seed")


def _exact(value: Any) -> Any:
    """A JSON-ready value with floats as their ``repr`` (exact, NaN included)."""
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, bool | int | str) or value is None:
        return value
    return str(value)


def format_transition(transition: Transition) -> str:
    """``t_s source>target reason[rule]`` with ``t_s`` exact (``repr``)."""
    rule = f"[{transition.rule}]" if transition.rule else ""
    return (
        f"{transition.t_s!r} {transition.source.value}>{transition.target.value} "
        f"{transition.reason}{rule}"
    )


def outcome_digest(result: TrialResult, transitions: Iterable[Transition]) -> str:
    """SHA-256 (16 hex digits) of ``result`` without ``wall_time_s`` and the transitions."""
    content = {
        "result": {name: _exact(getattr(result, name)) for name in RESULT_FIELDS},
        "transitions": [format_transition(t) for t in transitions],
    }
    text = json.dumps(content, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def truth_digest(truth: dict[str, np.ndarray] | None) -> str:
    """SHA-256 (16 hex digits) of the truth arrays (names, shapes, dtypes and values), or
    ``""`` without truth (on hardware)."""
    if truth is None:
        return ""
    digest = hashlib.sha256()
    for name in sorted(truth):
        values = np.ascontiguousarray(truth[name])
        digest.update(f"{name}:{values.dtype.str}:{values.shape};".encode())
        digest.update(values.tobytes())
    return digest.hexdigest()[:16]


def fingerprint_row(
    result: TrialResult,
    transitions: Sequence[Transition] = (),
    truth: dict[str, np.ndarray] | None = None,
) -> dict[str, str]:
    """The table's row for one trial (``COLUMNS``, as text): its result, the machine's
    transitions and the truth arrays (none for a trial that raised)."""
    row = {
        "outcome": outcome_digest(result, transitions),
        "truth": truth_digest(truth),
        "transitions": "; ".join(format_transition(t) for t in transitions),
    }
    for name in RESULT_FIELDS:
        value = _exact(getattr(result, name))
        row[name] = "" if value is None else str(value)
    return {column: row[column] for column in COLUMNS}


def trial_row(task: Task, task_name: str, controller: str, seed: int) -> dict[str, str]:
    """The row of one trial of ``task`` run now; a trial that raises is a row too, of status
    ``error`` (as the batch tools record it: ``evaluation.trials.guard``); a signal that
    stopped the trial stops the tool."""
    try:
        outcome = run(task, controller, seed)
    except Exception as exc:  # noqa: BLE001 -- a trial that raises is an outcome to compare
        spec = TrialSpec(task_name, controller, seed)
        return fingerprint_row(error_result(spec, f"{type(exc).__name__}: {exc}", 0.0))
    raise_if_interrupted(outcome)
    return fingerprint_row(outcome.result, outcome.transitions, outcome.truth)


def read_table(path: Path, option: str = "--against") -> dict[tuple[str, ...], dict[str, str]]:
    """A table written by ``--out``, by (task, controller, seed); ToolError naming ``option``
    if it is missing or not one."""
    if not path.is_file():
        raise ToolError(f"{option} '{path}': no such file; expected a CSV written by --out")
    try:
        with path.open(newline="") as handle:
            reader = csv.DictReader(handle)
            missing = [c for c in COLUMNS if c not in (reader.fieldnames or ())]
            if missing:
                raise ToolError(
                    f"{option} '{path}': not a trial fingerprint table (no column "
                    f"{', '.join(missing)}); expected a CSV written by --out"
                )
            return {tuple(row[k] for k in KEY): row for row in reader}
    except csv.Error as exc:
        raise ToolError(f"{option} '{path}': not a CSV file ({exc})") from None


def differences(before: dict[str, str], after: dict[str, str]) -> list[str]:
    """The columns whose text differs between two rows of one seed, as ``name: a -> b``."""
    return [
        f"{name}: {before[name]} -> {after[name]}"
        for name in COLUMNS
        if name not in KEY and before[name] != after[name]
    ]


def compare(
    rows: Sequence[dict[str, str]], earlier: dict[tuple[str, ...], dict[str, str]], path: Path
) -> list[str]:
    """The comparison's report lines: each seed that differs (or is not in ``earlier``),
    then the count of identical seeds."""
    lines, same = [], 0
    for row in rows:
        before = earlier.get(tuple(row[k] for k in KEY))
        if before is None:
            lines.append(f"seed {row['seed']}: not in '{path}'")
        elif before["outcome"] == row["outcome"] and before["truth"] == row["truth"]:
            same += 1
        else:
            lines.append(f"seed {row['seed']}: " + "; ".join(differences(before, row)))
    lines.append(f"{same} of {len(rows)} seeds identical to '{path}' (outcome and truth)")
    return lines


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog=job_prog(PROG), description=__doc__.splitlines()[0])
    parser.add_argument("--task", help="usb_c, usb_a or a task YAML path")
    parser.add_argument("--controller", choices=list(TRIAL_CONTROLLERS), default="dipole")
    parser.add_argument("--seeds", type=seeds_type, help="A:B, the seeds A up to B (B excluded)")
    add_override_argument(parser, "override a task key by dotted path (repeatable)")
    parser.add_argument("--out", type=Path, default=None, help="write the table to this CSV")
    parser.add_argument(
        "--against", type=Path, default=None, help="compare with this earlier table (--out's)"
    )
    parser.add_argument(
        "--compare",
        type=Path,
        nargs=2,
        metavar=("BEFORE", "AFTER"),
        help="compare two tables written by --out, running no trial",
    )
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.compare is not None:
        given = [name for name in ("task", "seeds", "out", "against") if getattr(args, name)]
        if given or args.overrides:
            parser.error(f"argument --compare: runs no trial; drop --{(given or ['set'])[0]}")
        return run_tool(PROG, lambda: _compare_tables(*args.compare))
    missing = [f"--{name}" for name in ("task", "seeds") if getattr(args, name) is None]
    if missing:
        parser.error(f"the following arguments are required: {', '.join(missing)}")
    return run_tool(PROG, lambda: _run(args))


def _compare_tables(before: Path, after: Path) -> int:
    earlier = read_table(before, "--compare")
    later = read_table(after, "--compare")
    print("\n".join(compare(list(later.values()), earlier, before)))
    absent = [key[2] for key in earlier if key not in later]
    if absent:
        print(f"{len(absent)} seeds of '{before}' are not in '{after}': {', '.join(absent)}")
    return 0


def _run(args: argparse.Namespace) -> int:
    task = load_task(args.task, args.overrides)
    earlier = None if args.against is None else read_table(args.against)
    if args.out is not None:
        check_output_file(args.out, [task.path, args.against])
    cv2.setNumThreads(1)
    writer = csv.DictWriter(sys.stdout, COLUMNS, lineterminator="\n")
    writer.writeheader()
    rows = []
    for seed in args.seeds:
        rows.append(trial_row(task, args.task, args.controller, seed))
        writer.writerow(rows[-1])
        sys.stdout.flush()
    if args.out is not None:
        with atomic_text(args.out, newline="") as handle:
            table = csv.DictWriter(handle, COLUMNS, lineterminator="\n")
            table.writeheader()
            table.writerows(rows)
        print(f"{PROG}: wrote {args.out}", file=sys.stderr)
    if earlier is not None:
        print("\n".join(compare(rows, earlier, args.against)))
    return 0
