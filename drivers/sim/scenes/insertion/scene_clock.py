"""The scene's clock: the clock the control loop and the twins sleep on moves the world.

``SceneClock(base)`` is a ``core.clock.Clock``: ``now()`` is the base clock's;
``sleep(s)`` first brings the world (``attach``) up to the present, then sleeps the base
clock until ``s`` after the call (``ManualClock``: at once, as fast as possible;
``MonotonicClock``: in real time, the physics' cost taken out of the wait). Whatever reads
the world later (a tactile frame) syncs it further itself, so the controller never calls
the scene.
"""

from __future__ import annotations

from collections.abc import Callable

from core.clock import Clock


class SceneClock:
    """See the module docstring."""

    def __init__(self, base: Clock) -> None:
        self._base = base
        self._sync: Callable[[float], None] | None = None

    def attach(self, sync: Callable[[float], None]) -> None:
        """Call ``sync(now)`` at every sleep."""
        self._sync = sync

    @property
    def base(self) -> Clock:
        """The clock the scene's time comes from."""
        return self._base

    def now(self) -> float:
        return self._base.now()

    def sleep(self, seconds: float) -> None:
        start = self._base.now()
        if self._sync is not None:
            self._sync(start)
        self._base.sleep(start + max(0.0, seconds) - self._base.now())
