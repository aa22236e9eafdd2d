"""What every command-line tool shares (the product's jobs and the research tools alike):
one-line errors, exit codes, signals, argument types (``--set KEY=VALUE`` overrides too).

Exit codes (docs/ARCHITECTURE.md, "Failure behaviour"):

* 0 -- done (warnings, if any, on stderr);
* 1 -- a device could not be reached or failed (a run on the robot): one line naming every
  device that was not ready and what to check;
* 2 -- bad input (argument, file, configuration) or an output that cannot be written: one
  line ``PROG: error: ...`` on stderr, never a traceback;
* 141 -- its standard output was closed early (``replay summary EP | head -1``): nothing
  more is written, no message, the code of a tool ended by SIGPIPE as standard tools are;
* 130 -- interrupted by SIGINT (Ctrl-C), 143 -- ended by SIGTERM: one line
  ``PROG: interrupted by SIGINT ...``. Outputs in progress are discarded (they are written
  to temporary files and renamed into place only when complete, ``controller.cli.outputs``), so
  an earlier result stays as it was.

Argument types for argparse (``type=``) refuse what is not finite, not in range, or not an
integer where a count is expected; argparse then exits with code 2 naming the option.
"""

from __future__ import annotations

import argparse
import math
import os
import signal
import sys
import threading
from collections.abc import Callable
from pathlib import Path

from core.config import CONFIG_ROOT, ConfigError, parse_override
from core.entry_point import (
    EXIT_SIGINT,
    EXIT_SIGPIPE,
    EXIT_SIGTERM,
    Terminated,
    raise_terminated,
    silence_closed_stdout,
    stop_behind,
)
from core.errors import DeviceError

EXIT_ERROR = 2
EXIT_DEVICE = 1  # a device could not be reached or failed (as tactile check-hardware)


class ToolError(Exception):
    """A problem with the user's input or outputs; the message is one line naming it."""


def one_line(text: object) -> str:
    """``text`` with every run of whitespace (newlines included) as one space."""
    return " ".join(str(text).split())


def describe_os_error(exc: OSError) -> str:
    """``'PATH': reason`` for an OSError, e.g. ``'x.csv': No space left on device``."""
    reason = exc.strerror or str(exc)
    return f"'{exc.filename}': {reason}" if exc.filename else reason


def run_tool(prog: str, body: Callable[[], int]) -> int:
    """Run a tool's ``body`` and map its failures to one stderr line and an exit code.

    SIGTERM is turned into ``Terminated`` while ``body`` runs (in the main thread), so
    ``finally`` blocks and the atomic writers clean up exactly as on Ctrl-C.
    """
    quiet_video_decoder()
    previous = None
    if threading.current_thread() is threading.main_thread():
        previous = signal.signal(signal.SIGTERM, raise_terminated)
    try:
        return body()
    except BrokenPipeError:  # the reader of stdout left (``| head``): end quietly
        silence_closed_stdout()
        return EXIT_SIGPIPE
    except (ToolError, ConfigError) as exc:
        print(f"{prog}: error: {one_line(exc)}", file=sys.stderr)
        return EXIT_ERROR
    except DeviceError as exc:
        print(f"{prog}: error: {one_line(exc)}", file=sys.stderr)
        return EXIT_DEVICE
    except OSError as exc:
        print(f"{prog}: error: {one_line(describe_os_error(exc))}", file=sys.stderr)
        return EXIT_ERROR
    except UnicodeDecodeError as exc:  # a binary file given where text was expected
        print(f"{prog}: error: an input is not UTF-8 text ({one_line(exc)})", file=sys.stderr)
        return EXIT_ERROR
    except KeyboardInterrupt:
        print(f"{prog}: interrupted by SIGINT; {_DISCARDED}", file=sys.stderr)
        return EXIT_SIGINT
    except Terminated:
        print(f"{prog}: ended by SIGTERM; {_DISCARDED}", file=sys.stderr)
        return EXIT_SIGTERM
    except ImportError as exc:  # a signal inside an extension module's initialisation
        stop = stop_behind(exc)
        if stop is None:
            raise
        stopped = "interrupted by SIGINT" if stop is KeyboardInterrupt else "ended by SIGTERM"
        print(f"{prog}: {stopped}; {_DISCARDED}", file=sys.stderr)
        return EXIT_SIGINT if stop is KeyboardInterrupt else EXIT_SIGTERM
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)


_DISCARDED = "unfinished outputs were discarded, earlier results are unchanged"


def ignore_interrupts_in_worker() -> None:
    """Pool initializer: workers leave SIGINT to the parent, which stops the pool (a worker
    interrupted mid-task would print its own traceback)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


# -- argument types -------------------------------------------------------------------------


def integer(low: int, high: int) -> Callable[[str], int]:
    """argparse type: a whole number in [low, high] (``1.5``, ``1e3``, ``nan`` refused)."""

    def parse(text: str) -> int:
        try:
            value = int(text.strip(), 10)
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"expected a whole number in [{low}, {high}], got {text!r}"
            ) from None
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(
                f"expected a whole number in [{low}, {high}], got {text!r}"
            )
        return value

    return parse


def number(low: float, high: float, unit: str = "") -> Callable[[str], float]:
    """argparse type: a finite number in [low, high] (``nan``, ``inf`` refused)."""
    what = f"a number{' of ' + unit if unit else ''} in [{low:g}, {high:g}]"

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}") from None
        if not (math.isfinite(value) and low <= value <= high):
            raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}")
        return value

    return parse


def number_list(low: float, high: float, unit: str) -> Callable[[str], tuple[float, ...]]:
    """argparse type: comma-separated finite numbers in [low, high], at least one."""
    single = number(low, high, unit)

    def parse(text: str) -> tuple[float, ...]:
        parts = text.split(",")
        try:
            return tuple(single(part) for part in parts)
        except argparse.ArgumentTypeError:
            raise argparse.ArgumentTypeError(
                f"expected comma-separated numbers of {unit} in [{low:g}, {high:g}], "
                f"e.g. 10,7, got {text!r}"
            ) from None

    return parse


SEED = integer(0, 2**32 - 1)


def nonblank(what: str) -> Callable[[str], str]:
    """argparse type: a text that is not empty or only spaces (``--task ''`` refused);
    ``what`` says what was expected, e.g. 'a task sentence'."""

    def parse(text: str) -> str:
        if not text.strip():
            raise argparse.ArgumentTypeError(f"expected {what}, got an empty text")
        return text

    return parse


def distinct(parser: argparse.ArgumentParser, option: str, values: list[str]) -> None:
    """Exit with a usage error (code 2) when ``values`` names something twice."""
    repeated = sorted({v for v in values if values.count(v) > 1})
    if repeated:
        parser.error(f"argument {option}: {repeated[0]!r} is given twice")


def resolved_config_path(name_or_path: str | None, folder: str) -> Path | None:
    """The file a configuration name stands for (configs/FOLDER/NAME.yaml) or the path
    itself; used to keep outputs off inputs. None for None."""
    if name_or_path is None:
        return None
    path = Path(name_or_path)
    return path if path.suffix in (".yaml", ".yml") else CONFIG_ROOT / folder / f"{path}.yaml"


def quiet_video_decoder() -> None:
    """Keep FFmpeg's own decoder messages off the terminal (the tools report damaged video
    in their own words); must run before the first capture is opened."""
    os.environ.setdefault("OPENCV_FFMPEG_LOGLEVEL", "-8")


def _override(text: str) -> str:
    try:
        parse_override(text)
    except ConfigError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return text


def add_override_argument(parser: argparse.ArgumentParser, help_text: str) -> None:
    """``--set KEY=VALUE`` (repeatable, into ``overrides``), each checked as it is parsed."""
    parser.add_argument(
        "--set",
        dest="overrides",
        metavar="KEY=VALUE",
        type=_override,
        action="append",
        default=[],
        help=help_text,
    )
