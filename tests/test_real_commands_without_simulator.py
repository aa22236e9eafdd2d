"""Every real-robot command starts, and fails only at the devices, with ``mujoco`` and the
simulator's packages (``drivers.sim``) made unimportable: a run on the robot never needs
the simulator. Each command runs as a user runs it, in its own process (the test is about
what that process imports)."""

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
runpy.run_path(sys.argv[0], run_name="__main__")
"""


def arm_file(tmp_path: Path) -> str:
    """The shipped robot file with the arm at an address where nothing listens."""
    path = tmp_path / "arm.yaml"
    text = (CONFIG_ROOT / "robot" / "xarm6.yaml").read_text()
    path.write_text(text.replace("ip: 192.168.1.185", "ip: 127.0.0.1"))
    return str(path)


def run_blocked(script: str, args: list[str], cwd: Path) -> subprocess.CompletedProcess:
    argv = [str(ROOT / "scripts" / f"{script}.py"), *args]
    code = textwrap.dedent(BLOCKED).replace("{argv!r}", repr(argv))
    return subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=cwd, timeout=120,
        env={"MPLBACKEND": "Agg", "SDL_VIDEODRIVER": "dummy", "PATH": "/usr/bin:/bin"},
    )  # fmt: skip


@pytest.mark.parametrize(
    ("script", "args", "prog"),
    [
        ("run_trial", ["--task", "usb_c", "--backend", "real", "--out", "{out}"], "run_trial"),
        ("teleop_demo", ["--backend", "real", "--no-view", "--out", "{out}"], "teleop_demo"),
        ("check_hardware", ["{arm}", "--backend", "real"], "check_hardware"),
    ],
)
def test_a_real_command_fails_only_at_the_devices_without_the_simulator(
    tmp_path, script, args, prog
):
    arm = arm_file(tmp_path)
    values = {"out": str(tmp_path / "out"), "arm": arm}
    argv = [a.format(**values) for a in args]
    if script != "check_hardware":
        argv += ["--set", f"devices.arm={arm}"]
    ran = run_blocked(script, argv, tmp_path)
    output = ran.stdout + ran.stderr
    assert "blocked:" not in output and "Traceback" not in output, output
    assert ran.returncode == 1, output
    assert "127.0.0.1" in output  # it got as far as the arm


def test_the_blocker_would_catch_a_simulator_import(tmp_path):
    ran = run_blocked("run_trial", ["--task", "usb_c", "--out", str(tmp_path / "o")], tmp_path)
    assert ran.returncode != 0 and "blocked: " in ran.stdout + ran.stderr
