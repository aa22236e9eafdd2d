"""What ``run_trial`` and ``teleop_demo`` say about how a run went, beyond its timeline.

* ``signal_exit``: a run stopped by SIGINT or SIGTERM (the loop's safe path) says so in one
  stderr line, as every tool does, naming what it kept, and exits 130 or 143;
* ``fault_exit``: a run that ended in a fault (a watchdog trip, an exception in a tick;
  always after a safe stop, controller/loop.py) prints one stderr line naming it and exits
  with ``EXIT_DEVICE`` (1: a device could not be reached or failed); other ends are 0.
* ``pace_line``: in the paced real-time simulation (``core.clock.PacedClock``) the world
  waits for a late tick, so a busy machine slows the run instead of making its robot late
  (and the overrun rule, unchanged, never sees a late tick there; it guards the real
  robot). The line says whether the simulation kept pace with the wall clock, or how far
  it fell behind, with the machine's load average.
"""

from __future__ import annotations

import os
import sys
from typing import Any

from controller.cli.support import EXIT_DEVICE, EXIT_SIGINT, EXIT_SIGTERM, one_line
from controller.loop import LoopResult


def signal_exit(prog: str, loop: LoopResult, kept: str) -> int | None:
    """130 or 143 after one stderr line if ``loop`` was stopped by SIGINT or SIGTERM (``kept``:
    what the run kept, e.g. its episode), else None."""
    if loop.reason != "signal":
        return None
    term = "SIGTERM" in loop.message
    word = "ended by SIGTERM" if term else "interrupted by SIGINT"
    print(f"{prog}: {word} (safe stop done); {kept}", file=sys.stderr)
    return EXIT_SIGTERM if term else EXIT_SIGINT


def fault_exit(prog: str, loop: LoopResult) -> int:
    """``EXIT_DEVICE`` after one stderr line if ``loop`` ended in a fault, else 0."""
    if loop.reason != "fault":
        return 0
    print(
        f"{prog}: error: the run ended in a fault (safe stop done): {one_line(loop.message)}",
        file=sys.stderr,
    )
    return EXIT_DEVICE


def load_text() -> str:
    """``load average L on C cores`` (the last minute's), or "" where unknown."""
    try:
        load = os.getloadavg()[0]
    except OSError:
        return ""
    return f"load average {load:.1f} on {os.cpu_count() or '?'} cores"


def pace_line(clock: Any) -> str | None:
    """How a paced simulation kept up with the wall clock up to now, None for a run on
    another clock. ``clock``: the run's (a ``SceneClock``; its ``now()``: s since the
    start)."""
    base = getattr(clock, "base", None)
    slipped_s = getattr(base, "slipped_s", None)
    if slipped_s is None:
        return None
    if slipped_s <= 0:
        return "real time: the simulation kept pace with the wall clock"
    load = load_text()
    return (
        f"real time: the simulation fell {slipped_s:.2f} s behind the wall clock over "
        f"{clock.now():.1f} s (a busy machine{': ' + load if load else ''}); the simulated "
        "world waited for the controller, so no tick was late on its clock"
    )
