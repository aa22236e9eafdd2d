"""How a script in scripts/ runs its tool: Ctrl-C and SIGTERM end it with one line at any
moment, the imports of the tool's (heavy) modules included.

A script is two lines, ``from core.entry_point import run_main`` and
``run_main("package.module")``. ``run_main`` turns SIGINT into KeyboardInterrupt and SIGTERM
into ``Terminated`` *before* it imports the tool's module, so a signal while NumPy, OpenCV
or MuJoCo load is handled like one during the work: the tool's own handler
(``controller.cli.support.run_tool``) reports it while the tool works, and
``run_main`` reports what reaches it (``PROG: interrupted by SIGINT``, exit 130;
``PROG: ended by SIGTERM``, exit 143; no traceback). Once ``main`` has returned, its outputs
are complete and a signal during the interpreter's shutdown ends the process at once with
the same code, silently. A signal inside an extension module's initialisation (SciPy's
``_highspy``: pybind11 turns the KeyboardInterrupt into ``ImportError: initialization
failed``, the KeyboardInterrupt as its cause) is the same stop (``stop_behind``). Only the
interpreter's own start-up (before the script's first line
runs, some tens of milliseconds) is beyond reach. Importing this module loads only the
standard library.

Python runs a signal's handler wherever the main thread is, and an exception raised inside a
weakref callback or a ``__del__`` (e.g. the import system's module-lock callback) is not
propagated but passed to ``sys.unraisablehook`` and dropped. ``run_main`` installs a hook
that sends such a lost KeyboardInterrupt or ``Terminated`` again as its signal, from a
short-lived thread, so it lands once the callback has returned.
"""

from __future__ import annotations

import importlib
import os
import signal
import sys
import threading
from pathlib import Path
from typing import NoReturn

EXIT_SIGINT = 128 + signal.SIGINT  # 130
EXIT_SIGTERM = 128 + signal.SIGTERM  # 143
EXIT_SIGPIPE = 128 + signal.SIGPIPE  # 141: the reader of stdout left (``| head``)


class Terminated(BaseException):
    """Raised in the main thread when the process receives SIGTERM."""


def raise_terminated(signum: int, frame: object) -> None:
    """A SIGTERM handler: raise ``Terminated`` where the main thread is."""
    raise Terminated()


def silence_closed_stdout() -> None:
    """Point stdout at /dev/null once its reader has left, so the interpreter's own flush
    at exit raises nothing (Python's advice for SIGPIPE, docs of ``signal``)."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError):  # no stdout file descriptor at all
        pass


def _exit_at_once(signum: int, frame: object) -> None:
    os._exit(128 + signum)


REDELIVERY_DELAY_S = 0.005
"""How long the re-sending thread waits: far longer than a callback that swallowed a stop."""

_STOP_SIGNALS = {KeyboardInterrupt: signal.SIGINT, Terminated: signal.SIGTERM}


def _redeliver_lost_stops(previous_hook):
    """An ``unraisablehook`` that sends a dropped stop again as its signal and passes every
    other unraisable exception to ``previous_hook``."""

    def hook(unraisable) -> None:
        signum = _STOP_SIGNALS.get(unraisable.exc_type)
        if signum is None:
            previous_hook(unraisable)
            return
        while True:
            try:
                threading.Timer(REDELIVERY_DELAY_S, os.kill, (os.getpid(), signum)).start()
                return
            except (KeyboardInterrupt, Terminated):  # on a loaded machine, the stop sent
                continue  # again landed before the hook returned: lost again, send it again

    return hook


def stop_behind(error: BaseException) -> type[BaseException] | None:
    """KeyboardInterrupt or ``Terminated`` if ``error`` was caused by one (an extension
    module whose initialisation a signal interrupted: pybind11 reports it as
    ``ImportError: initialization failed`` from the KeyboardInterrupt), else None."""
    seen: set[int] = set()
    cause: BaseException | None = error
    while cause is not None and id(cause) not in seen:
        seen.add(id(cause))
        if isinstance(cause, (KeyboardInterrupt, Terminated)):
            return type(cause)
        cause = cause.__cause__ or cause.__context__
    return None


def run_main(module: str, first: str | None = None) -> NoReturn:
    """Exit with the code of ``module.main()`` (None: 0), 130 on SIGINT, 143 on SIGTERM.
    ``first``: ``"module:function"`` to call before ``module`` is imported (e.g. to limit
    the threads of the numerical libraries it loads)."""
    signal.signal(signal.SIGINT, signal.default_int_handler)
    signal.signal(signal.SIGTERM, raise_terminated)
    sys.unraisablehook = _redeliver_lost_stops(sys.unraisablehook)
    stopped_by = None
    try:
        if first is not None:
            first_module, function = first.split(":")
            getattr(importlib.import_module(first_module), function)()
        code = importlib.import_module(module).main()
    except KeyboardInterrupt:
        code, stopped_by = EXIT_SIGINT, "interrupted by SIGINT"
    except Terminated:
        code, stopped_by = EXIT_SIGTERM, "ended by SIGTERM"
    except ImportError as error:  # a signal inside an extension module's initialisation
        stop = stop_behind(error)
        if stop is None:
            raise
        code, stopped_by = (
            (EXIT_SIGINT, "interrupted by SIGINT")
            if stop is KeyboardInterrupt
            else (EXIT_SIGTERM, "ended by SIGTERM")
        )
    signal.signal(signal.SIGINT, _exit_at_once)
    signal.signal(signal.SIGTERM, _exit_at_once)
    if stopped_by is not None:  # the name the tool runs under (``tactile trial``: core.subcommands)
        print(f"{Path(sys.argv[0]).stem}: {stopped_by}", file=sys.stderr)
    try:  # before a signal could end the process without flushing them
        sys.stdout.flush()
    except BrokenPipeError:  # the reader left (``| head``): quietly, as SIGPIPE would
        silence_closed_stdout()
        code = EXIT_SIGPIPE if code == 0 else code
    except (OSError, ValueError):
        pass
    try:
        sys.stderr.flush()
    except (OSError, ValueError):
        pass
    sys.exit(code)
