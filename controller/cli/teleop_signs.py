"""The alignment demo's sign checks: each manoeuvre of a gamepad script, the tilt torque it
should give, and the one an episode recorded (docs/USER_GUIDE.md has the drawing).

Manoeuvres in the sensor frame S at the demo's start (the plug upright, hole yaw ~0; with
configs/gamepad/xbox.yaml ``vy`` moves the TCP along B's y = S's z and ``wz`` turns it
about B's z = -S's y):

* translate along +S z (``vy`` > 0): the opening's wall holds the tip back, the gel pushes
  the plug along +S z at the grasp: **tau_x > 0** (and < 0 for -S z);
* rotate about +S y (``wz`` < 0): the opening's walls stop the plug's twist, the gel turns
  it on: **tau_y > 0** (and < 0 about -S y).

``manoeuvres(events)`` finds each push of ``vy`` or ``wz`` away from zero in a script;
``measured_signs(episode, ...)`` averages the estimate over each push's hold (from half a
second after it starts to its end) against the second before it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from controller.episode import Episode


class PadEvent(Protocol):
    """A gamepad script's event (the simulated pad's, drivers/sim/twins/gamepad.py): at
    ``t_s`` (s on the demo's clock) these ``axes`` take these values (in [-1, 1])."""

    @property
    def t_s(self) -> float: ...

    @property
    def axes(self) -> Mapping[str, float]: ...


AXES = {"vy": ("tau_x", 1.0), "wz": ("tau_y", -1.0)}
"""Pad action -> (the torque it drives, the sign of that torque per unit of the action)."""
SETTLE_S = 0.5
BEFORE_S = 1.0


@dataclass(frozen=True)
class Manoeuvre:
    """A push of ``action`` to ``value`` from ``start_s`` to ``end_s`` (script time, s)."""

    action: str
    value: float
    start_s: float
    end_s: float

    @property
    def torque(self) -> str:
        return AXES[self.action][0]

    @property
    def expected_sign(self) -> int:
        return int(np.sign(self.value * AXES[self.action][1]))


UNIT_CALIBRATED = "N*m"
UNIT_RAW = "raw mm"
"""The estimate's tilt torques: N*m with a calibration (the demo's tasks have one), else the
estimator's raw units (mm)."""


@dataclass(frozen=True)
class SignCheck:
    """One manoeuvre, its torque's change (``change``: hold mean minus the mean before, in
    ``unit``: ``UNIT_CALIBRATED`` or ``UNIT_RAW``; NaN if the episode does not cover it) and
    whether its sign is the expected one."""

    manoeuvre: Manoeuvre
    change: float
    unit: str = UNIT_CALIBRATED

    @property
    def ok(self) -> bool:
        return int(np.sign(self.change)) == self.manoeuvre.expected_sign


def manoeuvres(events: Sequence[PadEvent]) -> list[Manoeuvre]:
    """Every push of a sign-checked action away from zero and back, in time order."""
    found: list[Manoeuvre] = []
    open_: dict[str, tuple[float, float]] = {}
    for event in events:
        for action, value in event.axes.items():
            if action not in AXES:
                continue
            if action in open_:
                start_s, pushed = open_.pop(action)
                found.append(Manoeuvre(action, pushed, start_s, event.t_s))
            if value != 0.0:
                open_[action] = (event.t_s, float(value))
    return sorted(found, key=lambda m: m.start_s)


def measured_signs(
    episode: Episode, script: Sequence[Manoeuvre], start_s: float = 0.0
) -> list[SignCheck]:
    """Each manoeuvre of ``script`` (times from the demo's start at ``start_s`` on the
    episode's clock) checked against the episode's ``/tactile/wrench``."""
    values = [m.value for m in episode.messages("/tactile/wrench") if not m.value["zeroing"]]
    rows = [(v["t_s"], v["tau_x"], v["tau_y"]) for v in values]
    calibrated = bool(values) and all(v.get("calibrated", False) for v in values)
    unit = UNIT_CALIBRATED if calibrated else UNIT_RAW
    data = np.array([[np.nan if v is None else v for v in row] for row in rows], float)
    data = data.reshape(-1, 3)
    t = data[:, 0] - start_s
    checks = []
    for m in script:
        column = 1 if m.torque == "tau_x" else 2
        hold = (t >= m.start_s + SETTLE_S) & (t <= m.end_s)
        before = (t >= m.start_s - BEFORE_S) & (t < m.start_s)
        if not (np.isfinite(data[hold, column]).any() and np.isfinite(data[before, column]).any()):
            checks.append(SignCheck(m, math.nan, unit))  # not in the episode (it ended before)
            continue
        change = float(np.nanmean(data[hold, column]) - np.nanmean(data[before, column]))
        checks.append(SignCheck(m, change, unit))
    return checks
