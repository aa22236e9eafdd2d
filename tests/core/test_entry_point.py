"""Every script in scripts/ ends in one line on Ctrl-C or SIGTERM at any moment, while its
tool's modules are still being imported included (core/entry_point.py)."""

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


@pytest.mark.parametrize(
    "name, args, signum, after_s",
    [
        ("run_trial", ["--task", "usb_c", "--seed", "0"], signal.SIGINT, 0.3),
        ("run_trials", ["--task", "usb_c", "--seeds", "0:2"], signal.SIGINT, 0.6),
        ("estimate", ["frames"], signal.SIGINT, 0.15),
        ("estimate", ["frames"], signal.SIGTERM, 0.3),
        ("calibrate", ["dataset"], signal.SIGTERM, 0.6),
    ],
)
def test_a_signal_while_the_tool_loads_is_one_line_and_its_exit_code(
    tmp_path, name, args, signum, after_s
):
    process = subprocess.Popen(
        [sys.executable, str(ROOT / "scripts" / f"{name}.py"), *args, "--out", str(tmp_path / "o")],
        cwd=tmp_path,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    time.sleep(after_s)  # the interpreter has started; the tool's imports take seconds
    process.send_signal(signum)
    _, err = process.communicate(timeout=60)
    assert process.returncode == 128 + signum, err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    word = "interrupted by SIGINT" if signum == signal.SIGINT else "ended by SIGTERM"
    assert err.startswith(f"{name}: {word}"), err
