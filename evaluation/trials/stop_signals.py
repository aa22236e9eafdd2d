"""SIGINT and SIGTERM while a batch runs: the first one stops it, later ones are ignored.

The first signal raises KeyboardInterrupt (SIGINT) or ``Terminated`` (SIGTERM) in the main
thread at once, except while a finished trial is being recorded (its CSV row, its result,
its record folder): then as soon as that is done, so the batch's files always agree. From
the first signal on, both are ignored, so the clean-up (killing the workers, writing the
summary; well under a second) runs to its end. A signal the process ignored from the start
stays ignored; the previous handlers come back when the batch ends.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from types import FrameType
from typing import Any

from controller.cli.support import Terminated

STOPS: dict[int, type[BaseException]] = {
    signal.SIGINT: KeyboardInterrupt,
    signal.SIGTERM: Terminated,
}


class StopSignals:
    """Context manager installing the handlers above (main thread only)."""

    def __init__(self) -> None:
        self._previous: dict[int, Any] = {}
        self._recording = False
        self._pending: BaseException | None = None

    def __enter__(self) -> StopSignals:
        if threading.current_thread() is threading.main_thread():
            for signum in STOPS:
                if signal.getsignal(signum) is not signal.SIG_IGN:
                    self._previous[signum] = signal.signal(signum, self._on_signal)
        return self

    def __exit__(self, *exc_info: object) -> None:
        for signum, handler in self._previous.items():
            signal.signal(signum, handler)

    def ignore_further(self) -> None:
        """Ignore both signals until the batch ends (called once the batch is stopping)."""
        for signum in self._previous:
            signal.signal(signum, signal.SIG_IGN)

    @contextmanager
    def recording(self) -> Iterator[None]:
        """A block the first signal does not cut short; it is raised right after it."""
        self._recording = True
        try:
            yield
        finally:
            self._recording = False
        if self._pending is not None:
            raise self._pending

    def _on_signal(self, signum: int, frame: FrameType | None) -> None:
        del frame
        self.ignore_further()
        stop = STOPS[signum]()
        if self._recording:
            self._pending = stop
            return
        raise stop
