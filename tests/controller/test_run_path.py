"""The run path (controller/run/): a real run never loads the simulator, the controller
table is the one source of names, and every tick reaches every observer."""

import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from controller.insertion import Phase
from controller.run import CONTROLLERS, Controller, load_task, run_task
from controller.run.runner import controller_entry
from core.config import CONFIG_ROOT, ConfigError

ROOT = Path(__file__).resolve().parents[2]
SHORT = ("touch_spiral.timeout_s=3.0",)  # the grasp and the start of the approach only

BLOCKED_REAL_RUN = """
import importlib.abc, sys

class Blocker(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] == "mujoco" or name.startswith(("drivers.sim.", "drivers.sim")):
            raise ImportError(f"blocked: {name}")

sys.meta_path.insert(0, Blocker())
from controller.run import load_task, run_task
from core.errors import DeviceError

task = load_task("usb_c", ["devices.arm={arm}"], backend="real")
assert task.scene is None
try:
    run_task(task, "dipole", 0, backend="real")
except DeviceError as error:
    print("device error:", error)
loaded = [m for m in sys.modules if m.startswith("drivers.sim") or m.startswith("mujoco")]
print("simulator modules:", loaded)
"""


def test_a_real_run_never_loads_the_simulator_or_mujoco(tmp_path):
    """With imports of ``drivers.sim`` and ``mujoco`` blocked, a real run gets as far as
    connecting the arm (nothing listens at the address) and fails there, with a device
    error naming the address, not an import error (nor a refusal of the arm's file, which has
    no F/T sensor: the product does not read one)."""
    arm = tmp_path / "arm.yaml"
    text = (CONFIG_ROOT / "robot" / "xarm6.yaml").read_text()
    arm.write_text(text.replace("ip: 192.168.1.185", "ip: 127.0.0.1"))
    code = textwrap.dedent(BLOCKED_REAL_RUN).replace("{arm}", str(arm))
    ran = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, timeout=120
    )
    assert ran.returncode == 0, ran.stderr
    assert "device error: arm, gripper, tactile, gamepad: not ready: " in ran.stdout
    assert "arm: xarm6: cannot connect to the controller at 127.0.0.1" in ran.stdout
    assert "simulator modules: []" in ran.stdout


def test_the_blocker_would_catch_a_simulator_import(tmp_path):
    code = textwrap.dedent(BLOCKED_REAL_RUN).split("from controller.run")[0]
    code += "import drivers.sim.scenes.insertion\n"
    ran = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert ran.returncode != 0 and "blocked: drivers.sim" in ran.stderr


def test_the_controller_table_names_every_controller_once():
    assert list(CONTROLLERS) == [
        "dipole", "fingervision", "zero_torque", "torque_only", "align", "blind",
    ]  # fmt: skip
    assert [n for n, c in CONTROLLERS.items() if c.arm_force] == ["blind"]  # the product: no F/T
    with pytest.raises(ConfigError, match="controller 'oracle': expected one of dipole, "):
        controller_entry("oracle", "sim", CONTROLLERS)
    truth_reader = Controller(CONTROLLERS["dipole"].machine, lambda est, world: est, True)
    with pytest.raises(ConfigError, match="controller 'peek' reads the simulator's truth"):
        controller_entry("peek", "real", {"peek": truth_reader})
    assert controller_entry("peek", "sim", {"peek": truth_reader}) is truth_reader


def test_every_tick_and_transition_reaches_every_observer(tmp_path):
    first, second = [], []
    outcome = run_task(
        load_task("usb_c", SHORT), "dipole", 1, out_dir=tmp_path / "r",
        observers=(first.append, second.append),
    )  # fmt: skip
    assert outcome.loop.reason == "failed" and outcome.machine.phase is Phase.FAILED
    assert len(first) == len(second) == outcome.loop.stats.ticks
    seen = [t for tick in first for t in tick.transitions]
    assert seen == list(outcome.transitions) and len(seen) >= 2
    recorded = (tmp_path / "r" / "transitions.jsonl").read_text().splitlines()
    assert len(recorded) == len(seen)
    assert outcome.devices.world is not None  # the simulated world, for scoring only


def test_a_sim_run_needs_the_task_loaded_with_its_scene():
    with pytest.raises(ConfigError, match="loaded without its scene"):
        run_task(load_task("usb_c", backend="real"), "dipole", 0)


def test_a_bad_scene_key_is_refused_for_sim_and_unread_for_real():
    bad = ("scene.friction=-1",)
    with pytest.raises(ConfigError, match="key 'scene.friction'"):
        load_task("usb_c", bad)
    assert load_task("usb_c", bad, backend="real").scene is None


@pytest.mark.parametrize(
    "override, message",
    [
        ("estimator=nonexistent", r"key 'estimator': unknown estimator configuration"),
        ("estimator=/etc/passwd", r"key 'estimator': unknown estimator configuration"),
        ("devices.tactile=/etc/passwd", r"key 'devices.tactile': /etc/passwd: expected a mapping"),
        (
            "devices.tactile=robot/xarm6.yaml",
            r"key 'devices.tactile': .*xarm6.yaml: key 'type': expected a device of kind 'tactile'",
        ),
        ("devices.arm=/dev/null", r"key 'devices.arm': /dev/null is not a regular file"),
        ("devices.gripper=absent.yaml", r"key 'devices.gripper': .*absent.yaml does not exist"),
    ],
)
@pytest.mark.parametrize("backend", ["sim", "real"])
def test_a_bad_estimator_or_device_file_is_refused_when_the_task_loads(override, message, backend):
    """Refused by load_task (so by every tool, a batch's check included), naming the task
    file and the key, not at the first trial's start."""
    with pytest.raises(ConfigError, match=r"usb_c.yaml: " + message) as caught:
        load_task("usb_c", (override,), backend=backend)
    assert "\n" not in str(caught.value)
