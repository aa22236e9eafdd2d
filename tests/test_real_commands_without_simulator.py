"""Every real-robot command starts, and fails only at the devices, with ``mujoco`` and the
simulator's packages (``drivers.sim``) made unimportable: a run on the robot never needs
the simulator. Each command runs as a user runs it, through ``tactile``, in its own process
(the test is about what that process imports)."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from core.config import CONFIG_ROOT

ROOT = Path(__file__).resolve().parents[1]

BLOCKED = """
import importlib.abc, runpy, sys

class Blocker(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] == "mujoco" or name.split(".")[:2] == ["drivers", "sim"]:
            raise ImportError(f"blocked: {name}")

sys.meta_path.insert(0, Blocker())
sys.argv = {argv!r}
runpy.run_module("controller.cli.command", run_name="__main__", alter_sys=True)
"""


def arm_file(tmp_path: Path) -> str:
    """The shipped robot file with the arm at an address where nothing listens."""
    path = tmp_path / "arm.yaml"
    text = (CONFIG_ROOT / "robot" / "xarm6.yaml").read_text()
    path.write_text(text.replace("ip: 192.168.1.185", "ip: 127.0.0.1"))
    return str(path)


def run_blocked(job: str, args: list[str], cwd: Path) -> subprocess.CompletedProcess:
    """``tactile JOB ARGS`` in a new process in which the simulator cannot be imported."""
    argv = ["tactile", job, *args]
    code = textwrap.dedent(BLOCKED).replace("{argv!r}", repr(argv))
    return subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=cwd, timeout=120,
        env={"MPLBACKEND": "Agg", "SDL_VIDEODRIVER": "dummy", "PATH": "/usr/bin:/bin",
             "PYTHONPATH": str(ROOT)},
    )  # fmt: skip


@pytest.mark.parametrize(
    ("job", "args"),
    [
        ("trial", ["--task", "usb_c", "--backend", "real", "--out", "{out}"]),
        ("teleop", ["--backend", "real", "--no-view", "--out", "{out}"]),
        ("check-hardware", ["{arm}", "--backend", "real"]),
    ],
)
def test_a_real_command_fails_only_at_the_devices_without_the_simulator(tmp_path, job, args):
    arm = arm_file(tmp_path)
    values = {"out": str(tmp_path / "out"), "arm": arm}
    argv = [a.format(**values) for a in args]
    if job != "check-hardware":
        argv += ["--set", f"devices.arm={arm}"]
    ran = run_blocked(job, argv, tmp_path)
    output = ran.stdout + ran.stderr
    assert "blocked:" not in output and "Traceback" not in output, output
    assert ran.returncode == 1, output
    assert "127.0.0.1" in output  # it got as far as the arm


@pytest.mark.parametrize(
    ("job", "args"),
    [
        ("estimate", ["{missing}", "--out", "{out}"]),
        ("calibrate", ["{missing}"]),
        ("replay", ["summary", "{missing}"]),
    ],
)
def test_an_offline_command_starts_without_the_simulator(tmp_path, job, args):
    """The tools on recorded data: a missing input is refused in one line (exit 2), as with
    the simulator, and nothing they load needs it."""
    values = {"missing": str(tmp_path / "missing"), "out": str(tmp_path / "out.csv")}
    argv = [a.format(**values) for a in args]
    ran = run_blocked(job, argv, tmp_path)
    output = ran.stdout + ran.stderr
    assert "blocked:" not in output and "Traceback" not in output, output
    assert ran.returncode == 2 and "missing" in ran.stderr, output


def test_the_command_help_starts_without_the_simulator(tmp_path):
    ran = run_blocked("--help", [], tmp_path)
    assert ran.returncode == 0 and "check-hardware" in ran.stdout, ran.stderr


def test_the_blocker_would_catch_a_simulator_import(tmp_path):
    ran = run_blocked("trial", ["--task", "usb_c", "--out", str(tmp_path / "o")], tmp_path)
    assert ran.returncode != 0 and "blocked: " in ran.stdout + ran.stderr
