"""The one time source of the device layer: every real driver and every twin reads time from
an injected ``Clock`` and never from ``time`` directly (``core.devices`` re-exports it).

* ``now()`` -- seconds on a monotonic scale; samples are stamped with it (``t_s``), and
  ages, step budgets and polling deadlines are measured on it;
* ``sleep(seconds)`` -- what a device calls where it waits on its own time line (the
  Hand-E's activation polling and command pacing, ``SimArm.move_to`` with ``wait=True``,
  ``SimGripper.activate``).

``PacedClock`` is simulated time that waits for the wall clock (the interactive real-time
simulation: a busy computer slows it rather than making its robot late).
``MonotonicClock`` (the default everywhere) is ``time.monotonic`` and ``time.sleep``: the
devices run in real time beside a real control loop. A run's devices share one
``MonotonicClock.from_now()``, whose time starts at 0 when the run's devices are built (as
``ManualClock``'s does), so every time a run records or prints is seconds from its start,
whichever clock it ran on. ``ManualClock`` only moves when told
(``advance(dt_s)``), and its ``sleep`` advances it at once, so tests and scenes run
deterministically and as fast as the machine allows.

Waits on the operating system (a socket, a serial port, a camera thread) are not on the
clock: the real drivers bound them in real seconds (``connect_timeout_s``, ``io_timeout_s``,
``timeout_s`` in their YAML), so a silent device fails in bounded wall time whatever clock
is injected.

The twins integrate their state lazily: each call first brings the twin's state up to
``now()`` (in fixed steps where the model has dynamics), so the result depends only on the
clock readings and the commands, not on how often the twin is polled.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Protocol, runtime_checkable


@runtime_checkable
class Clock(Protocol):
    """A monotonic time source in seconds, and the way to wait on it."""

    def now(self) -> float: ...

    def sleep(self, seconds: float) -> None: ...


class MonotonicClock:
    """Real time: ``time.monotonic()`` less ``origin_s`` (s; 0: the machine's uptime) and
    ``time.sleep()``."""

    def __init__(self, origin_s: float = 0.0) -> None:
        if not math.isfinite(origin_s):
            raise ValueError(f"origin_s: expected a finite number, got {origin_s!r}")
        self.origin_s = float(origin_s)

    @classmethod
    def from_now(cls) -> MonotonicClock:
        """A clock reading 0 now: seconds since it was made."""
        return cls(time.monotonic())

    def now(self) -> float:
        return time.monotonic() - self.origin_s

    def sleep(self, seconds: float) -> None:
        time.sleep(max(0.0, seconds))


class PacedClock:
    """Simulated time paced to the wall clock, for a simulation a person watches or drives:
    ``now()`` starts at 0 and moves only in ``sleep(s)``, which advances it by ``s`` and then
    waits until as much wall time has passed. Work between sleeps (the physics, the
    controller's tick) takes no simulated time, so the simulated world waits for a late
    tick instead of moving on without it: a loaded computer slows the simulation, it never
    makes its robot late. When the wall clock has run more than ``MAX_BEHIND_S`` ahead, the
    simulation does not race to catch up: the lag is let go and added to ``slipped_s``
    (s of wall time the simulation fell behind in all)."""

    MAX_BEHIND_S = 0.05

    def __init__(
        self,
        wall: Callable[[], float] = time.monotonic,
        wait: Callable[[float], None] = time.sleep,
    ) -> None:
        self._wall, self._wait = wall, wait
        self._origin_s = wall()
        self._now_s = 0.0
        self.slipped_s = 0.0

    def now(self) -> float:
        return self._now_s

    def sleep(self, seconds: float) -> None:
        """Advance by ``seconds`` (>= 0; negative waits are no-ops) and wait for the wall."""
        self._now_s += max(0.0, seconds)
        ahead = self._now_s - (self._wall() - self._origin_s)
        if ahead > 0:
            self._wait(ahead)
        elif -ahead > self.MAX_BEHIND_S:
            self._origin_s -= ahead  # let the lag go: the simulation stays behind the wall
            self.slipped_s -= ahead


class ManualClock:
    """Simulated time that moves only through ``advance`` (or ``sleep``, which advances)."""

    def __init__(self, start_s: float = 0.0) -> None:
        if not math.isfinite(start_s):
            raise ValueError(f"start_s: expected a finite number, got {start_s!r}")
        self._now_s = float(start_s)

    def now(self) -> float:
        return self._now_s

    def advance(self, dt_s: float) -> None:
        """Move time forward by ``dt_s`` seconds (>= 0)."""
        if not math.isfinite(dt_s) or dt_s < 0:
            raise ValueError(f"dt_s: expected a finite number >= 0, got {dt_s!r}")
        self._now_s += dt_s

    def sleep(self, seconds: float) -> None:
        """Advance by ``seconds`` (negative waits are no-ops, as for ``time.sleep(0)``)."""
        self.advance(max(0.0, seconds))
