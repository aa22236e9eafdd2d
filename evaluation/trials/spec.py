"""What one trial of a batch is asked to do (``TrialSpec``) and the function that does it.

A ``TrialFunction`` takes a ``TrialSpec`` and returns the trial's ``TrialResult``. It must be
a module-level function (the local executor's worker processes and Ray's workers import it
by name), deterministic for a given spec apart from ``wall_time_s``, and may raise: the
batch turns an exception into a failed result (``failure_reason`` ``"error: ..."``).

The module that defines it may also define ``check_spec(spec: TrialSpec) -> None``, which
the batch calls once in the parent before any trial runs; it raises ``ConfigError`` (one
line) for a task, controller or override the trial function would refuse, so that a typo is
one error and exit code 2, not a batch of error trials.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import overload

from controller.cli.support import ToolError
from controller.run.insertion_trial import MAX_SEED
from controller.run.result import TrialResult
from evaluation.trials.oracle import TRIAL_CONTROLLERS
from evaluation.trials.records import unfinished_record


class SpecError(ToolError, ValueError):
    """A batch argument (seeds, controller, override) is malformed; the message is one line."""


@dataclass(frozen=True)
class TrialSpec:
    """One trial: ``task`` (a task configuration name, e.g. usb_c, or a YAML path),
    ``controller`` (a name of ``TRIAL_CONTROLLERS``), ``seed`` (the scene's seed), ``overrides``
    (``"KEY=VALUE"`` strings applied in order to the task configuration by dotted path, see
    ``core.config.apply_overrides``) and ``out_dir`` (where the trial writes its own
    record and charts; None: it writes nothing); ``episode``: the trial also writes its
    episode (``episode.mcap``) in ``out_dir``."""

    task: str
    controller: str
    seed: int
    overrides: tuple[str, ...] = ()
    out_dir: Path | None = None
    episode: bool = False

    def __post_init__(self) -> None:
        if self.episode and self.out_dir is None:
            raise SpecError("episode: a trial writes its episode into its out_dir; give one")
        if self.controller not in TRIAL_CONTROLLERS:
            raise SpecError(
                f"controller {self.controller!r}: expected one of {', '.join(TRIAL_CONTROLLERS)}"
            )
        if not 0 <= self.seed <= MAX_SEED:
            raise SpecError(f"seed {self.seed}: expected a whole number in [0, {MAX_SEED}]")
        object.__setattr__(self, "overrides", tuple(self.overrides))


TrialFunction = Callable[[TrialSpec], TrialResult]


class SeedSpecs(Sequence[TrialSpec]):
    """The trials of one batch: ``controller`` on ``task`` with ``overrides``, one per seed
    of ``seeds``, each made only when asked for, so a batch of any length takes the same
    memory. With ``records`` (a folder), each trial writes its record in its unfinished
    folder under it (``evaluation.trials.records``), and with ``episodes`` its episode too."""

    def __init__(
        self,
        task: str,
        controller: str,
        seeds: range,
        overrides: tuple[str, ...] = (),
        records: Path | None = None,
        episodes: bool = False,
    ) -> None:
        if episodes and records is None:
            raise SpecError("episodes: each trial's episode goes into its record; give records")
        self.task, self.controller, self.seeds = task, controller, seeds
        self.overrides, self.records, self.episodes = tuple(overrides), records, episodes

    def __len__(self) -> int:
        return len(self.seeds)

    @overload
    def __getitem__(self, index: int) -> TrialSpec: ...

    @overload
    def __getitem__(self, index: slice) -> SeedSpecs: ...

    def __getitem__(self, index: int | slice) -> TrialSpec | SeedSpecs:
        if isinstance(index, slice):
            return SeedSpecs(
                self.task,
                self.controller,
                self.seeds[index],
                self.overrides,
                self.records,
                self.episodes,
            )
        seed = self.seeds[index]
        out_dir = None
        if self.records is not None:
            out_dir = unfinished_record(self.records, self.controller, seed)
        return TrialSpec(self.task, self.controller, seed, self.overrides, out_dir, self.episodes)


def parse_seeds(text: str) -> range:
    """``'A:B'`` -> the seeds A, A+1, ..., B-1 (B excluded); SpecError otherwise."""
    match = re.fullmatch(r"\s*(\d+)\s*:\s*(\d+)\s*", text)
    if not match:
        raise SpecError(f"seeds {text!r}: expected A:B, whole numbers with A < B, e.g. 0:200")
    start, stop = int(match.group(1)), int(match.group(2))
    if stop <= start:
        raise SpecError(f"seeds {text!r}: expected A < B (B is excluded), e.g. 0:200")
    if stop - 1 > MAX_SEED:
        raise SpecError(f"seeds {text!r}: seeds must be at most {MAX_SEED}")
    return range(start, stop)


def format_seeds(seeds: range) -> str:
    """The ``A:B`` text of a seed range."""
    return f"{seeds.start}:{seeds.stop}"
