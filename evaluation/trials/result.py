"""The outcome of one insertion trial, as the batch tools collect it."""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any


@dataclass(frozen=True)
class TrialResult:
    """One trial's outcome.

    ``task``: the task name (usb_a, usb_c); ``controller``: which torques drove the machine
    (dipole, fingervision, blind, oracle); ``seed``: the scene's seed; ``success``: the plug
    reached the depth and the machine ended in DONE; ``failure_reason``: the FAILED
    transition's reason (None on success); ``time_to_insert_s``: simulated time from the
    controller's first tick (the devices' start-up, such as the gripper's activation, comes
    before it) to reaching the depth (None when it never did); ``duration_s``: simulated time of
    the whole run; ``max_true_force_n``: the largest true contact force between plug and
    board or receptacle (ground truth, N); ``force_limit_n``: the task's limit on it;
    ``wall_time_s``: the wall-clock time the trial took.
    """

    task: str
    controller: str
    seed: int
    success: bool
    failure_reason: str | None
    time_to_insert_s: float | None
    duration_s: float
    max_true_force_n: float
    force_limit_n: float
    wall_time_s: float

    def as_row(self) -> dict[str, Any]:
        """The result as a flat dict (one CSV row)."""
        return asdict(self)
