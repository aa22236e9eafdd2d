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

* ``batch.json``: what decides the batch's trials (its context without how they ran:
  task, controller, seeds, overrides, ...; and how many were asked for), written first.

The output folder must be new or empty (``check_batch_folder``), checked before any trial
runs. A batch stopped before its end (a signal, a crash, the machine turned off) is
continued with ``resume``: its ``batch.json`` must equal the new run's, its finished rows
are kept (an incomplete last row, from a kill in mid-write, is dropped) with their records,
the unfinished records removed, and only the trials without a row run. Every batch of the
run is checked before any is changed, so a refused resume changes nothing.
"""

from __future__ import annotations

import csv
import dataclasses
import io
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

from controller.cli.outputs import atomic_file, check_output_folder, write_text
from controller.cli.support import Terminated, ToolError, one_line
from controller.run.result import LATER_FIELDS, TrialResult
from evaluation.trials.executors import Executor
from evaluation.trials.records import (
    RECORDS,
    discard_unfinished_records,
    keep_record,
    kept_record,
)
from evaluation.trials.spec import TrialFunction, TrialSpec
from evaluation.trials.stop_signals import StopSignals
from evaluation.trials.summary import summarize

CSV_NAME = "trials.csv"
SUMMARY_NAME = "summary.json"
PLAN_NAME = "batch.json"
RUN_KEYS = ("executor", "workers", "ray_address")  # how the trials ran, not which
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
    for name in (CSV_NAME, SUMMARY_NAME, PLAN_NAME):
        if (path / name).exists():
            raise ToolError(
                f"{option} '{path}' already holds a batch ({name}); choose a new folder "
                "(or remove it first, or continue it with --resume)"
            )
    raise ToolError(
        f"{option} '{path}' is not empty and holds no batch; expected a new or empty folder"
    )


def check_resume_folder(path: Path, option: str = "--out") -> None:
    """Refuse to resume in ``path`` unless it is a folder (each batch in it is checked when
    the run starts: ``run_batches``)."""
    if not path.is_dir():
        raise ToolError(f"{option} '{path}': not a folder holding a run to resume")


class TrialLog:
    """``trials.csv`` of one batch, one row appended and synced per result; ``append``:
    continue the file (a resumed batch), else create it."""

    def __init__(self, path: Path, append: bool = False) -> None:
        path.parent.mkdir(parents=True, exist_ok=True)
        self._handle: TextIO = open(path, "a" if append else "x", newline="")
        self._writer = csv.DictWriter(self._handle, fieldnames=CSV_COLUMNS)
        if not append:
            self._writer.writeheader()
        self._sync()

    def write(self, result: TrialResult) -> None:
        self._writer.writerow(_csv_row(result))
        self._sync()

    def _sync(self) -> None:
        self._handle.flush()
        os.fsync(self._handle.fileno())

    def close(self) -> None:
        self._handle.close()


def _csv_row(result: TrialResult) -> dict[str, Any]:
    """``result`` as ``trials.csv`` writes it."""
    return {k: _cell(v) for k, v in result.as_row().items()}


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


def _plan(batch: Batch) -> dict[str, Any]:
    """What decides ``batch``'s trials (``batch.json``)."""
    decided = {k: v for k, v in batch.context.items() if k not in RUN_KEYS}
    return _json_safe({**decided, "requested": len(batch.specs)})


def _rows(path: Path, older: bool = False) -> list[dict[str, str]]:
    """The complete rows of a ``trials.csv`` (none when it is missing or empty: a batch
    stopped before its first row). Every row is written whole with its line end, so a last
    line without one, or a last row short of fields, is the row of a kill in mid-write and
    is dropped; a short row elsewhere is a damaged file (ToolError). Its columns must be
    this version's; with ``older``, a table from before some of its later columns existed
    (``LATER_FIELDS``: they read as unknown) is taken too."""
    if not path.is_file():
        return []
    with open(path, newline="") as handle:
        text = handle.read()
    if not text:
        return []
    reader = csv.DictReader(io.StringIO(text[: text.rfind("\n") + 1]))
    columns = tuple(reader.fieldnames or ())
    if columns != CSV_COLUMNS and not (older and _older_columns(columns)):
        raise ToolError(f"'{path}': not a trials.csv of this version (its columns differ)")
    rows = list(reader)
    whole = [None not in row and None not in row.values() for row in rows]
    if rows and not whole[-1]:
        rows.pop()
        whole.pop()
    if not all(whole):
        raise ToolError(f"'{path}': row {whole.index(False) + 1} is damaged (fields missing)")
    return rows


def _older_columns(columns: tuple[str, ...]) -> bool:
    """``columns`` are this version's in its order, less some of ``LATER_FIELDS``."""
    kept = tuple(c for c in CSV_COLUMNS if c in columns)
    return kept == columns and set(CSV_COLUMNS) - set(columns) <= set(LATER_FIELDS)


def read_table(path: Path) -> list[TrialResult]:
    """The results of the finished rows of the ``trials.csv`` at ``path``, this version's or
    older (``_rows``); ToolError naming the file if it is not one or has a bad row."""
    try:
        rows = _rows(path, older=True)
    except UnicodeDecodeError:
        raise ToolError(f"'{path}': not UTF-8 text; expected a trials.csv") from None
    results = []
    for number, row in enumerate(rows, start=1):
        try:
            results.append(TrialResult.from_row(row))
        except (KeyError, TypeError, ValueError) as exc:
            raise ToolError(f"'{path}': row {number} is bad ({one_line(exc)})") from None
    return results


def read_trials(folder: Path) -> list[TrialResult]:
    """The finished trials of the batch folder ``folder`` (its ``trials.csv``, this version's
    or older: ``read_table``); ToolError naming it if it has no table or no finished trial."""
    path = folder / CSV_NAME
    if not path.is_file():
        raise ToolError(f"'{folder}' holds no {CSV_NAME}; expected a batch's folder")
    results = read_table(path)
    if not results:
        raise ToolError(f"'{path}': no finished trial in it")
    return results


def read_batch(folder: Path) -> tuple[dict[str, Any], list[TrialResult]]:
    """A batch folder's plan (``batch.json``) and the results of its finished rows, for the
    tools that read a batch after it ran; ToolError naming the file if either is missing or
    not this version's."""
    plan_path = folder / PLAN_NAME
    if not plan_path.is_file():
        raise ToolError(f"'{folder}' holds no {PLAN_NAME}; expected a batch's folder")
    try:
        plan = json.loads(plan_path.read_text())
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ToolError(f"'{plan_path}': not a batch plan ({one_line(exc)})") from None
    if not isinstance(plan, dict) or not isinstance(plan.get("task"), str):
        raise ToolError(f"'{plan_path}': not a batch plan (no task named)")
    return plan, read_table(folder / CSV_NAME)


def _finished(batch: Batch) -> list[tuple[TrialResult, TrialSpec]]:
    """The trials of ``batch`` that finished before it stopped, with their specs, read and
    checked for a resume without changing anything (ToolError naming the problem)."""
    plan_path = batch.out_dir / PLAN_NAME
    if not plan_path.is_file():
        raise ToolError(f"--resume: '{batch.out_dir}' holds no batch to resume ({PLAN_NAME})")
    earlier, plan = json.loads(plan_path.read_text()), _plan(batch)
    for key in sorted(set(earlier) | set(plan)):
        if earlier.get(key) != plan.get(key):
            raise ToolError(
                f"--resume: '{batch.out_dir}' was run with {key} {earlier.get(key)!r}, not "
                f"{plan.get(key)!r}; resume with the same arguments"
            )
    by_seed = {spec.seed: spec for spec in batch.specs}
    if len(by_seed) != len(batch.specs):
        raise ToolError(f"--resume: '{batch.out_dir}': a resumed batch needs one trial per seed")
    csv_path = batch.out_dir / CSV_NAME
    finished: list[tuple[TrialResult, TrialSpec]] = []
    seen: set[int] = set()
    for row in _rows(csv_path):
        try:
            result = TrialResult.from_row(row)
        except (KeyError, TypeError, ValueError) as exc:
            raise ToolError(f"--resume: '{csv_path}': a bad row ({one_line(exc)})") from None
        spec = by_seed.get(result.seed)
        if spec is None or (spec.task, spec.controller) != (result.task, result.controller):
            raise ToolError(
                f"--resume: '{csv_path}': seed {result.seed} ({result.task}, "
                f"{result.controller}) is not one of this batch's trials"
            )
        if result.seed in seen:
            raise ToolError(f"--resume: '{csv_path}': seed {result.seed} has two rows")
        record = spec.out_dir
        if record is not None and record.exists() and kept_record(record).exists():
            raise ToolError(f"--resume: '{record}': its trial's record exists twice")
        seen.add(result.seed)
        finished.append((result, spec))
    return finished


def _continued(batch: Batch, finished: list[tuple[TrialResult, TrialSpec]]) -> list[TrialSpec]:
    """Continue ``batch`` from its ``finished`` trials (``_finished``): they go into
    ``batch.results``, ``trials.csv`` is rewritten with them alone, their records kept
    (a kill between a row and its record's rename leaves it hidden) and the other hidden
    records removed. Returns the trials still to run."""
    with atomic_file(batch.out_dir / CSV_NAME) as temporary:
        with open(temporary, "w", newline="") as handle:
            writer = csv.DictWriter(handle, fieldnames=CSV_COLUMNS)
            writer.writeheader()
            writer.writerows(_csv_row(result) for result, _ in finished)
    for _, spec in finished:
        if spec.out_dir is not None:
            keep_record(spec.out_dir)
    discard_unfinished_records(batch.out_dir / RECORDS)
    batch.results.extend(result for result, _ in finished)
    done = {spec.seed for _, spec in finished}
    return [spec for spec in batch.specs if spec.seed not in done]


def _pending(batches: Sequence[Batch], resume: bool) -> dict[int, Sequence[TrialSpec]]:
    """The trials still to run per batch (by ``id``): all (each batch's ``batch.json``
    written; its specs as they are, made only when asked for), or when resuming those
    without a row, every batch checked before any is changed (a resume holds the batch's
    specs in memory)."""
    if not resume:
        for batch in batches:
            write_text(batch.out_dir / PLAN_NAME, json.dumps(_plan(batch), indent=2) + "\n")
        return {id(b): b.specs for b in batches}
    finished = [_finished(b) for b in batches]
    return {id(b): _continued(b, f) for b, f in zip(batches, finished, strict=True)}


def success_so_far(successes: int, done: int) -> str:
    """The progress bar's note: the trials inserted of those finished (a resumed run's
    earlier ones included), as a count and a percentage."""
    return f"inserted {successes}/{done} ({100.0 * successes / done:.1f}%)"


def write_summary(path: Path, summary: Mapping[str, Any]) -> None:
    """``summary`` as indented JSON at ``path``, atomically."""
    write_text(path, json.dumps(_json_safe(summary), indent=2) + "\n")


def run_batches(
    function: TrialFunction,
    batches: Sequence[Batch],
    executor: Executor,
    progress: bool = True,
    on_result: Callable[[TrialResult], None] | None = None,
    resume: bool = False,
) -> str | None:
    """Run every batch's trials on ``executor`` and record them (module doc); fills each
    batch's ``results`` and ``summary``. Returns None when every trial finished, or the
    signal (``"SIGINT"``, ``"SIGTERM"``) that stopped the run, after the summaries of what
    finished are written. The progress bar goes to stderr: the trials done of those to run,
    the time so far and tqdm's estimate of the time left, and ``success_so_far``. ``resume``:
    continue batches stopped before their end (module doc; ToolError, before any trial
    runs, when one cannot be)."""
    in_flight: dict[TrialSpec, Batch] = {}
    pending = _pending(batches, resume)

    def submitted() -> Iterator[TrialSpec]:
        for batch in batches:
            for spec in pending[id(batch)]:
                if spec in in_flight:
                    raise ValueError(f"trial {spec} is given twice")
                in_flight[spec] = batch
                yield spec

    stopped: str | None = None
    with StopSignals() as signals:
        try:
            with executor, ExitStack() as stack:
                logs = {
                    id(b): stack.enter_context(closing(TrialLog(b.out_dir / CSV_NAME, resume)))
                    for b in batches
                }
                bar = stack.enter_context(
                    tqdm(
                        total=sum(len(p) for p in pending.values()),
                        unit="trial",
                        file=sys.stderr,
                        disable=not progress,
                    )
                )
                successes = sum(r.success for b in batches for r in b.results)
                done = sum(len(b.results) for b in batches)
                for spec, result in executor.run(function, submitted()):
                    with signals.recording():
                        batch = in_flight.pop(spec)
                        logs[id(batch)].write(result)
                        batch.results.append(result)
                        if spec.out_dir is not None:
                            keep_record(spec.out_dir)
                    successes += result.success
                    done += 1
                    bar.set_postfix_str(success_so_far(successes, done), refresh=False)
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
