"""Every script in scripts/ ends in one line on Ctrl-C or SIGTERM at any moment, while its
tool's modules are still being imported included (core/entry_point.py)."""

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SCRIPTS = sorted((ROOT / "scripts").glob("*.py"))


@pytest.mark.parametrize("script", SCRIPTS, ids=lambda path: path.stem)
def test_every_script_runs_its_tool_through_run_main(script):
    text = script.read_text()
    assert "from core.entry_point import run_main\n" in text
    assert re.search(r'run_main\(\s*"[\w.]+"', text), "the tool's module is imported by run_main"
    assert "import main" not in text


# Run a script with an import hook that holds the first import of NumPy (which every tool
# loads, and core.entry_point does not) until the signal comes, and says when it holds.
HOLD_NUMPY = """
import runpy, sys, time

class HoldNumPy:
    def find_spec(self, name, path=None, target=None):
        if name == "numpy":
            sys.meta_path.remove(self)
            print("loading", flush=True)
            time.sleep(60)
        return None

sys.meta_path.insert(0, HoldNumPy())
sys.argv = sys.argv[1:]
runpy.run_path(sys.argv[0], run_name="__main__")
"""


@pytest.mark.parametrize(
    "name, args, signum",
    [
        ("run_trial", ["--task", "usb_c", "--seed", "0"], signal.SIGINT),
        ("run_trials", ["--task", "usb_c", "--seeds", "0:2"], signal.SIGINT),
        ("estimate", ["frames"], signal.SIGINT),
        ("estimate", ["frames"], signal.SIGTERM),
        ("calibrate", ["dataset"], signal.SIGTERM),
    ],
)
def test_a_signal_while_the_tool_loads_is_one_line_and_its_exit_code(tmp_path, name, args, signum):
    script = ROOT / "scripts" / f"{name}.py"
    process = subprocess.Popen(
        [sys.executable, "-c", HOLD_NUMPY, str(script), *args, "--out", str(tmp_path / "o")],
        cwd=tmp_path,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert process.stdout.readline() == "loading\n"  # the tool is importing NumPy now
        process.send_signal(signum)
        _, err = process.communicate(timeout=30)
    finally:  # a failure leaves no process running into the next test
        process.kill()
        process.communicate()
    assert process.returncode == 128 + signum, err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    word = "interrupted by SIGINT" if signum == signal.SIGINT else "ended by SIGTERM"
    assert err.startswith(f"{name}: {word}"), err


# A tool whose main() loses a stop the way a signal handler's exception is lost inside a
# weakref callback or __del__ (Python prints "Exception ignored" and goes on), then works on.
LOSES_A_STOP = """
import time
from core.entry_point import Terminated

class DropsAStop:
    def __del__(self):
        raise {stop}()

def main():
    DropsAStop()  # no reference left: __del__ runs here, and Python drops what it raises
    time.sleep(20)
    return 0
"""


def _run_main_on(folder: Path, prog: str, source: str) -> subprocess.CompletedProcess:
    """Run ``run_main`` as script ``prog`` on a tool module with ``source``, in a new process."""
    (folder / f"{prog}_tool.py").write_text(source)
    runner = (
        f"import sys; sys.path[:0] = [{str(folder)!r}, {str(ROOT)!r}]; sys.argv = [{prog!r}]\n"
        f"from core.entry_point import run_main\nrun_main('{prog}_tool')"
    )
    command = [sys.executable, "-c", runner]
    return subprocess.run(command, capture_output=True, text=True, timeout=60)


@pytest.mark.parametrize(
    "stop, code, word",
    [("KeyboardInterrupt", 130, "interrupted by SIGINT"), ("Terminated", 143, "ended by SIGTERM")],
)
def test_a_stop_lost_in_a_callback_is_sent_again_and_still_ends_the_tool(
    tmp_path, stop, code, word
):
    started = time.monotonic()
    done = _run_main_on(tmp_path, "lossy", LOSES_A_STOP.format(stop=stop))
    assert done.returncode == code, done.stderr
    assert done.stderr.strip() == f"lossy: {word}"
    assert time.monotonic() - started < 15  # not after the 20 s of work


def test_other_unraisable_exceptions_still_reach_the_previous_hook(tmp_path):
    tool = "class Drops:\n    def __del__(self):\n        raise ValueError('lost in __del__')\n"
    done = _run_main_on(tmp_path, "noisy", tool + "def main():\n    Drops()\n    return 0\n")
    assert done.returncode == 0
    assert "Exception ignored" in done.stderr and "lost in __del__" in done.stderr


# pybind11 (SciPy's _highspy) turns a KeyboardInterrupt during a module's initialisation into
# ImportError("initialization failed") from it.
STOPPED_IN_AN_EXTENSION = """
try:
    raise {stop}()
except BaseException as stop:
    raise ImportError("initialization failed") from stop

def main():
    return 0
"""


@pytest.mark.parametrize(
    "stop, code, word",
    [("KeyboardInterrupt", 130, "interrupted by SIGINT"), ("Terminated", 143, "ended by SIGTERM")],
)
def test_a_stop_inside_an_extension_modules_import_is_the_same_stop(tmp_path, stop, code, word):
    source = "from core.entry_point import Terminated\n" + STOPPED_IN_AN_EXTENSION.format(stop=stop)
    done = _run_main_on(tmp_path, "ext", source)
    assert done.returncode == code, done.stderr
    assert done.stderr.strip() == f"ext: {word}"


def test_an_import_error_of_its_own_is_still_a_traceback(tmp_path):
    source = "import no_such_module_here\ndef main():\n    return 0\n"
    done = _run_main_on(tmp_path, "broken", source)
    assert done.returncode == 1 and "ModuleNotFoundError" in done.stderr


def test_a_reader_that_leaves_early_ends_the_tool_quietly(tmp_path):
    (tmp_path / "chatty_tool.py").write_text(
        "from controller.cli.support import run_tool\n"
        "def main():\n"
        "    return run_tool('chatty', lambda: [print('line', i) for i in range(100000)] and 0)\n"
    )
    runner = (
        f"import sys; sys.path[:0] = [{str(tmp_path)!r}, {str(ROOT)!r}]; sys.argv = ['chatty']\n"
        "from core.entry_point import run_main\nrun_main('chatty_tool')"
    )
    read_end, write_end = os.pipe()
    os.close(read_end)  # the reader (``| head``) has gone before the first line
    try:
        done = subprocess.run(
            [sys.executable, "-c", runner], stdout=write_end, stderr=subprocess.PIPE,
            text=True, timeout=60,
        )  # fmt: skip
    finally:
        os.close(write_end)
    assert done.returncode == 128 + signal.SIGPIPE
    assert done.stderr == ""
