"""The one time source of the device layer: every real driver and every twin reads time from
an injected ``Clock`` and never from ``time`` directly (``core.devices`` re-exports it).

* ``now()`` -- seconds on a monotonic scale; samples are stamped with it (``t_s``), and
  ages, step budgets and polling deadlines are measured on it;
* ``sleep(seconds)`` -- what a device calls where it waits on its own time line (the
  Hand-E's activation polling and command pacing, ``SimArm.move_to`` with ``wait=True``,
  ``SimGripper.activate``).

``MonotonicClock`` (the default everywhere) is ``time.monotonic`` and ``time.sleep``: the
devices run in real time beside a real control loop. ``ManualClock`` only moves when told
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
from typing import Protocol, runtime_checkable


@runtime_checkable
class Clock(Protocol):
    """A monotonic time source in seconds, and the way to wait on it."""

    def now(self) -> float: ...

    def sleep(self, seconds: float) -> None: ...


class MonotonicClock:
    """Real time: ``time.monotonic()`` and ``time.sleep()``."""

    def now(self) -> float:
        return time.monotonic()

    def sleep(self, seconds: float) -> None:
        time.sleep(max(0.0, seconds))


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
