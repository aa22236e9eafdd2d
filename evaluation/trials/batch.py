"""Run batches of trials and record them: ``trials.csv`` streamed, ``summary.json`` at the end.

A batch is a list of ``TrialSpec`` and an output folder. ``run_batches`` runs several at
once on one executor (the comparison grid shares one pool or one Ray instance) and sends
each result to its batch's folder as it arrives:

* ``trials.csv``: one row per finished trial (``TrialResult.as_row()``), in the order they
  finished, flushed and synced to disk row by row, so a crash loses no finished trial;
* ``summary.json``: ``evaluation.trials.summary.summarize`` plus the batch's context,
  written atomically when the batch ends -- also when Ctrl-C or SIGTERM stops it, then with
  ``"complete": false`` and only the trials that finished.

A trial's own record (``TrialSpec.out_dir``) is kept under its name right after its row
(``evaluation.trials.records``); when the batch stops early, the records of the trials that
did not finish are removed, so the records, ``trials.csv`` and ``summary.json`` agree. A
signal that arrives while a finished trial is recorded takes effect right after it, and
later signals are ignored while the batch stops (``evaluation.trials.stop_signals``).

The output folder must be new or empty (``check_batch_folder``), checked before any trial
runs.
"""

from __future__ import annotations

import csv
import dataclasses
import json
import math
import os
import sys
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import ExitStack, closing
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TextIO

from tqdm import tqdm

from evaluation.common.cli_support import Terminated, ToolError
from evaluation.common.outputs import check_output_folder, write_text
from evaluation.trials.executors import Executor
from evaluation.trials.records import RECORDS, discard_unfinished_records, keep_record
from evaluation.trials.result import TrialResult
from evaluation.trials.spec import TrialFunction, TrialSpec
from evaluation.trials.stop_signals import StopSignals
from evaluation.trials.summary import summarize

CSV_NAME = "trials.csv"
SUMMARY_NAME = "summary.json"
CSV_COLUMNS = tuple(f.name for f in dataclasses.fields(TrialResult))


@dataclass
class Batch:
    """Trials whose results are recorded together in ``out_dir``; ``context`` goes into the
    summary (task, controller, seeds, overrides, executor, workers, ...)."""

    specs: Sequence[TrialSpec]
    out_dir: Path
    context: Mapping[str, Any] = field(default_factory=dict)
    results: list[TrialResult] = field(default_factory=list, init=False)
    summary: dict[str, Any] = field(default_factory=dict, init=False)


def check_batch_folder(path: Path, option: str = "--out") -> None:
    """Refuse an output folder that cannot be written or is not empty: one that holds an
    earlier batch (either file) is named so; any other content (a task file, a trial's
    record, ...) is refused as well, so a batch never writes beside or over it."""
    check_output_folder(path, option=option)
    if not path.is_dir() or not any(path.iterdir()):
        return
    for name in (CSV_NAME, SUMMARY_NAME):
        if (path / name).exists():
            raise ToolError(
                f"{option} '{path}' already holds a batch ({name}); choose a new folder "
                "(or remove it first)"
            )
    raise ToolError(
        f"{option} '{path}' is not empty and holds no batch; expected a new or empty folder"
    )


class TrialLog:
    """``trials.csv`` of one batch, one row appended and synced per result."""

    def __init__(self, path: Path) -> None:
        path.parent.mkdir(parents=True, exist_ok=True)
        self._handle: TextIO = open(path, "x", newline="")
        self._writer = csv.DictWriter(self._handle, fieldnames=CSV_COLUMNS)
        self._writer.writeheader()
        self._sync()

    def write(self, result: TrialResult) -> None:
        self._writer.writerow({k: _cell(v) for k, v in result.as_row().items()})
        self._sync()

    def _sync(self) -> None:
        self._handle.flush()
        os.fsync(self._handle.fileno())

    def close(self) -> None:
        self._handle.close()


def _cell(value: Any) -> Any:
    if value is None:
        return ""
    if isinstance(value, float):
        return repr(value)
    return value


def _json_safe(value: Any) -> Any:
    """``value`` with non-finite floats as None (JSON has no NaN) and tuples as lists."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, Mapping):
        return {str(k): _json_safe(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_json_safe(v) for v in value]
    return value


def write_summary(path: Path, summary: Mapping[str, Any]) -> None:
    """``summary`` as indented JSON at ``path``, atomically."""
    write_text(path, json.dumps(_json_safe(summary), indent=2) + "\n")


def run_batches(
    function: TrialFunction,
    batches: Sequence[Batch],
    executor: Executor,
    progress: bool = True,
    on_result: Callable[[TrialResult], None] | None = None,
) -> str | None:
    """Run every batch's trials on ``executor`` and record them (module doc); fills each
    batch's ``results`` and ``summary``. Returns None when every trial finished, or the
    signal (``"SIGINT"``, ``"SIGTERM"``) that stopped the run, after the summaries of what
    finished are written. The progress bar goes to stderr."""
    in_flight: dict[TrialSpec, Batch] = {}

    def submitted() -> Iterator[TrialSpec]:
        for batch in batches:
            for spec in batch.specs:
                if spec in in_flight:
                    raise ValueError(f"trial {spec} is given twice")
                in_flight[spec] = batch
                yield spec

    stopped: str | None = None
    with StopSignals() as signals:
        try:
            with executor, ExitStack() as stack:
                logs = {
                    id(b): stack.enter_context(closing(TrialLog(b.out_dir / CSV_NAME)))
                    for b in batches
                }
                bar = stack.enter_context(
                    tqdm(
                        total=sum(len(b.specs) for b in batches),
                        unit="trial",
                        file=sys.stderr,
                        disable=not progress,
                    )
                )
                successes = 0
                for spec, result in executor.run(function, submitted()):
                    with signals.recording():
                        batch = in_flight.pop(spec)
                        logs[id(batch)].write(result)
                        batch.results.append(result)
                        if spec.out_dir is not None:
                            keep_record(spec.out_dir)
                    successes += result.success
                    bar.set_postfix(succeeded=successes, refresh=False)
                    bar.update(1)
                    if on_result is not None:
                        on_result(result)
        except KeyboardInterrupt:
            stopped = "SIGINT"
        except Terminated:
            stopped = "SIGTERM"
        signals.ignore_further()
        for batch in batches:
            discard_unfinished_records(batch.out_dir / RECORDS)
            batch.summary = summarize(
                batch.results,
                **batch.context,
                requested=len(batch.specs),
                complete=stopped is None,
            )
            write_summary(batch.out_dir / SUMMARY_NAME, batch.summary)
    return stopped
