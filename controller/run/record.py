"""A run's minimal record (until the episode format of the episode issue), a loop observer:
written as the run goes, so a crash loses at most the last second.

``DIR/ticks.jsonl``: one JSON object per control tick (time, phase, the estimate the machine
saw, the command as sent and the machine's rule and sub-stage that decided it, the TCP
pose, the gripper width, the limits that acted, a fault), flushed every ``FLUSH_TICKS``
ticks and at the end (a write that fails, e.g. on a full disk, cuts the file at its last
flushed tick and raises an OSError naming it, which the loop turns into a fault: a safe
stop);
``DIR/transitions.jsonl``: every phase change with its reason and rule, flushed at once. At
the end ``DIR/trial.json`` (task, resolved configuration, seed, controller, outcome) is
written atomically; in simulation the trial tools add ``DIR/truth.npz`` (the simulator's
ground truth, which the controller never saw).
"""

from __future__ import annotations

import contextlib
import json
import math
import os
from pathlib import Path
from typing import IO, Any

from controller.loop import TickRecord
from controller.tactile.wrench import VALUE_FIELDS
from core.atomic_files import atomic_text

FLUSH_TICKS = 100


def _finite(value: float) -> float | None:
    return value if math.isfinite(value) else None


class JsonLines:
    """A file of JSON lines, flushed every ``flush_every`` rows and on ``close``. A failure
    to write (a full disk, a file size limit) leaves the file cut at its last flushed row, so
    what is there parses, and raises OSError naming the file."""

    def __init__(self, path: Path, flush_every: int) -> None:
        self.path = path
        self.flush_every = flush_every
        self._stream: IO[str] = path.open("w")
        self._rows = 0
        self._flushed_bytes = 0

    def write(self, row: dict[str, Any]) -> None:
        try:
            self._stream.write(json.dumps(row) + "\n")
            self._rows += 1
            if self._rows % self.flush_every == 0:
                self._flush()
        except OSError as error:
            self._cut(error)

    def close(self) -> None:
        if self._stream.closed:
            return
        try:
            self._flush()
        except OSError as error:
            self._cut(error)
        finally:
            self._stream.close()

    def _flush(self) -> None:
        self._stream.flush()
        self._flushed_bytes = self._stream.tell()

    def _cut(self, error: OSError) -> None:
        """Drop the unflushed rows (a partial line among them) and raise ``error`` with the
        file's name."""
        with contextlib.suppress(OSError):
            self._stream.close()  # its buffer cannot be written either
        with contextlib.suppress(OSError):
            os.truncate(self.path, self._flushed_bytes)
        raise OSError(error.errno, error.strerror, str(self.path)) from error


class RunRecorder:
    """The loop's observer: streams ticks, and the machine's transitions as they happen,
    into ``folder``."""

    def __init__(self, folder: Path) -> None:
        folder.mkdir(parents=True, exist_ok=True)
        self.folder = folder
        self._ticks = JsonLines(folder / "ticks.jsonl", FLUSH_TICKS)
        self._transitions = JsonLines(folder / "transitions.jsonl", 1)

    def __call__(self, tick: TickRecord) -> None:
        obs, command = tick.observation, tick.command
        row: dict[str, Any] = {
            "t_s": obs.t_s,
            "phase": tick.phase.value,
            "tcp_xyz_m": list(obs.arm.tcp.xyz_m),
            "tcp_rpy_rad": list(obs.arm.tcp.rpy_rad),
            "gripper_width_m": obs.gripper.width_m,
            "limited": list(tick.limited),
            "fault": tick.fault,
            "overran": tick.timing.overran,
        }
        if obs.wrench is not None:
            row["estimate"] = {k: _finite(getattr(obs.wrench, k)) for k in VALUE_FIELDS}
            row["estimate_t_s"] = obs.wrench.t_s
            row["calibrated"] = obs.wrench.calibrated
            row["contact"] = obs.wrench.contact
            row["slip"] = obs.wrench.slip_suspected
        if command is not None:
            row["rule"] = command.rule
            row["stage"] = command.stage
        if command is not None and command.twist is not None:
            row["twist"] = [*command.twist.linear_m_s, *command.twist.angular_rad_s]
        if command is not None and command.gripper is not None:
            row["gripper_target_m"] = command.gripper.width_m
        self._ticks.write(row)
        for transition in tick.transitions:
            self._transitions.write(
                {
                    "t_s": transition.t_s,
                    "from": transition.source.value,
                    "to": transition.target.value,
                    "reason": transition.reason,
                    "rule": transition.rule,
                }
            )

    def close(self) -> None:
        """Flush and close both files (each is closed even if the other fails)."""
        try:
            self._ticks.close()
        finally:
            self._transitions.close()

    def write_summary(self, summary: dict[str, Any]) -> None:
        """``trial.json``: the run's ``summary``, atomically."""
        with atomic_text(self.folder / "trial.json") as handle:
            json.dump(summary, handle, indent=2, default=str)
