"""A trial's minimal record (until the episode format of the episode issue): written as the
run goes, so a crash loses at most the last second.

``DIR/ticks.jsonl``: one JSON object per control tick (time, phase, the estimate the machine
saw, the command as sent, the TCP pose, the gripper width, the limits that acted, a fault),
flushed every ``FLUSH_TICKS`` ticks and at the end; ``DIR/transitions.jsonl``: every phase
change with its reason, flushed at once. At the end ``DIR/truth.npz`` (the simulator's ground
truth, which the controller never saw) and ``DIR/trial.json`` (task, resolved configuration,
seed, controller, outcome) are written atomically.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import IO, Any

import numpy as np

from controller.insertion import Machine, Transition
from controller.loop import TickRecord
from controller.tactile.wrench import VALUE_FIELDS
from evaluation.common.outputs import atomic_text

FLUSH_TICKS = 100


def _finite(value: float) -> float | None:
    return value if math.isfinite(value) else None


class TrialRecorder:
    """The loop's observer: streams ticks, and ``machine``'s transitions as they happen,
    into ``folder``."""

    def __init__(self, folder: Path, machine: Machine) -> None:
        folder.mkdir(parents=True, exist_ok=True)
        self.folder = folder
        self.machine = machine
        self._seen = 0
        self._ticks: IO[str] = (folder / "ticks.jsonl").open("w")
        self._transitions: IO[str] = (folder / "transitions.jsonl").open("w")
        self._count = 0

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
            row["contact"] = obs.wrench.contact
            row["slip"] = obs.wrench.slip_suspected
        if command is not None and command.twist is not None:
            row["twist"] = [*command.twist.linear_m_s, *command.twist.angular_rad_s]
        if command is not None and command.gripper is not None:
            row["gripper_target_m"] = command.gripper.width_m
        self._ticks.write(json.dumps(row) + "\n")
        self._count += 1
        if self._count % FLUSH_TICKS == 0:
            self._ticks.flush()
        transitions = self.machine.transitions
        for transition in transitions[self._seen :]:
            self._write_transition(transition)
        self._seen = len(transitions)

    def _write_transition(self, transition: Transition) -> None:
        self._transitions.write(
            json.dumps(
                {
                    "t_s": transition.t_s,
                    "from": transition.source.value,
                    "to": transition.target.value,
                    "reason": transition.reason,
                }
            )
            + "\n"
        )
        self._transitions.flush()

    def close(self) -> None:
        for stream in (self._ticks, self._transitions):
            if not stream.closed:
                stream.flush()
                stream.close()

    def write_truth(self, truth: dict[str, np.ndarray], hole: dict[str, float]) -> None:
        """The ground truth arrays and the true hole pose, atomically."""
        staging = self.folder / "truth.npz.partial"
        with staging.open("wb") as handle:
            np.savez_compressed(handle, **truth, **{f"hole_{k}": v for k, v in hole.items()})
        staging.replace(self.folder / "truth.npz")

    def write_summary(self, summary: dict[str, Any]) -> None:
        with atomic_text(self.folder / "trial.json") as handle:
            json.dump(summary, handle, indent=2, default=str)
