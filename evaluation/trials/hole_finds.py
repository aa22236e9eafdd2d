"""Where the plug's tip really was each time SEARCH declared the hole found, and what the
press that followed did: the diagnosis of false hole finds (``python -m evaluation hole_finds``).

The controller never sees this: it is read from the simulator's truth after the trial. The
tip is the centre of the plug's tip face, in the opening's frame O (origin at the true
opening's centre on the board surface, u along its width, v across it, z up). The *pivot
error* is the horizontal distance between that true tip and the tip the machine assumes
(the arm's TCP plus the plug's length along T z), which the compliant wrist separates; the
machine turns about the assumed one. A tilted plug
resting on the surface holds its tip centre at the *resting height* (half the leading face's
extent times the sine of the tilt); a tip at least ``DROP_M`` below that has dropped into
the opening.
"""

from __future__ import annotations

import json
import math
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from controller.insertion import Phase
from controller.insertion.motion import tip_position
from controller.run.task import Task
from core.devices import Pose
from evaluation.trials.trial import raise_if_interrupted, run

DROP_M = 1e-4  # a tip this far below its resting height is in the opening (m)


@dataclass(frozen=True)
class HoleFind:
    """One ``hole_found``: ``t_s`` simulated time; ``rule`` the rule that fired it
    (``torque_catch``, ``load_drop``, both joined by ``+``); ``tip_o_m`` the true tip centre
    in O (m);
    ``in_opening`` the tip dropped at least ``DROP_M`` below its resting height; ``outcome``
    what ended the attempt: ``inserted``, ``not_engaged``, ``jam``, or the failure or other
    guard that ended it; ``pivot_error_m`` the pivot error (m) at the find and when the
    attempt's ALIGN ended (NaN if it did not)."""

    seed: int
    t_s: float
    rule: str
    tip_o_m: tuple[float, float, float]
    in_opening: bool
    outcome: str
    pivot_error_m: tuple[float, float]


def resting_height_m(task: Task) -> float:
    """The tip centre's height (m) above the surface when the tilted plug rests on it: half
    the extent of the face across the tilt axis times the sine of the tilt."""
    plug, approach = task.config.plug, task.config.machine.approach
    across = plug.thickness_m if approach.tilt_axis == "x" else plug.width_m
    return 0.5 * across * math.sin(abs(approach.tilt_rad))


def trial_hole_finds(task: Task, seed: int) -> tuple[bool, list[HoleFind]]:
    """Run one simulated trial of ``task`` with the align controller; its success and each
    of its hole finds. A signal that stopped the trial stops the caller too
    (``raise_if_interrupted``)."""
    with tempfile.TemporaryDirectory() as folder:
        outcome = run(task, "align", seed, out_dir=Path(folder) / "trial")
        raise_if_interrupted(outcome)
        truth = dict(np.load(Path(folder) / "trial" / "truth.npz"))
        with (Path(folder) / "trial" / "ticks.jsonl").open() as lines:
            ticks = [json.loads(line) for line in lines]
    tick_t = np.array([tick["t_s"] for tick in ticks])
    length_m = task.config.plug.length_m

    def pivot_error(t_s: float) -> float:
        tick = ticks[_index_at(tick_t, t_s)]
        assumed = tip_position(Pose(tuple(tick["tcp_xyz_m"]), tuple(tick["tcp_rpy_rad"])), length_m)
        true_tip = truth["tip_xyz_b"][_index_at(truth["t_s"], tick["t_s"])]
        return float(np.linalg.norm((true_tip - assumed)[:2]))

    opening = np.array([truth["hole_x_m"], truth["hole_y_m"], truth["hole_z_m"]], dtype=float)
    to_o = Rotation.from_euler("z", float(truth["hole_yaw_rad"])).inv()
    resting = resting_height_m(task)
    transitions = outcome.transitions
    finds = []
    for i, tr in enumerate(transitions):
        if tr.reason != "hole_found":
            continue
        tip = to_o.apply(truth["tip_xyz_b"][_index_at(truth["t_s"], tr.t_s)] - opening)
        later = transitions[i + 1 :]
        aligned = _aligned_t_s(later)
        finds.append(
            HoleFind(
                seed,
                tr.t_s,
                tr.rule,
                tuple(float(x) for x in tip),
                bool(tip[2] <= resting - DROP_M),
                _attempt_outcome(later),
                (pivot_error(tr.t_s), math.nan if aligned is None else pivot_error(aligned)),
            )
        )
    return outcome.result.success, finds


def _index_at(times: np.ndarray, t_s: float) -> int:
    """The index of the first of the ascending ``times`` at or after ``t_s`` (the last if
    none)."""
    return min(int(np.searchsorted(times, t_s)), len(times) - 1)


def _aligned_t_s(later) -> float | None:
    """When the ALIGN begun by a hole find ended aligned (its next transition), or None."""
    return later[0].t_s if later and later[0].reason == "aligned" else None


def _attempt_outcome(later) -> str:
    """What ended the attempt begun by a hole find: the first of a release (inserted), a
    back-off, a failure or another phase's start."""
    for tr in later:
        if tr.target is Phase.RELEASE:
            return "inserted"
        if tr.target in (Phase.BACKOFF, Phase.FAILED, Phase.GRASP, Phase.TELEOP, Phase.ESTOP):
            return tr.reason
    return "run ended"


def summary_lines(finds: list[HoleFind]) -> list[str]:
    """Counts of hole finds by where the tip was and how the attempt ended, then by the rule
    that fired them and where the tip was; the pivot errors' median and range."""
    lines = []
    for where, flag in (("in the opening", True), ("on the surface", False)):
        group = [f for f in finds if f.in_opening is flag]
        counts: dict[str, int] = {}
        for f in group:
            counts[f.outcome] = counts.get(f.outcome, 0) + 1
        detail = ", ".join(f"{k} {v}" for k, v in sorted(counts.items(), key=lambda x: -x[1]))
        lines.append(f"{where}: {len(group)}" + (f" ({detail})" if detail else ""))
    for rule in sorted({f.rule for f in finds}):
        group = [f for f in finds if f.rule == rule]
        inside = sum(f.in_opening for f in group)
        lines.append(f"by {rule or 'no rule'}: {len(group)} ({inside} in the opening)")
    for when, column in (("at the finds", 0), ("when ALIGN ended", 1)):
        errors = np.array([f.pivot_error_m[column] for f in finds], dtype=float)
        errors = 1e3 * errors[np.isfinite(errors)]
        if errors.size:
            lines.append(
                f"pivot error {when} ({errors.size}): median {np.median(errors):.2f} mm, "
                f"{errors.min():.2f}-{errors.max():.2f} mm"
            )
    return lines
