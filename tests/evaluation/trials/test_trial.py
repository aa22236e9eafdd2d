"""The single-trial tool: task files, overrides, the information barrier, the record."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import types
from pathlib import Path

import numpy as np
import pytest

from controller.cli.support import Terminated
from controller.cli.trial_cli import main
from controller.loop import ControlLoop
from controller.run.task import load_task
from core.config import CONFIG_ROOT, ConfigError
from drivers.sim.scenes.insertion import TruthLog
from evaluation.trials import trial
from evaluation.trials.oracle import TrueWrench
from evaluation.trials.spec import TrialSpec

ROOT = Path(__file__).resolve().parents[3]

SHORT = ("touch_spiral.timeout_s=6.0",)  # the grasp, the approach and the search's start


def test_both_task_files_load_whole():
    for name in ("usb_a", "usb_c"):
        task = load_task(name)
        assert task.config.task == name
        assert task.config.plug.width_m < task.scene.receptacle.width_m


@pytest.mark.parametrize(
    ("override", "message"),
    [
        ("scene.friction=abc", "key 'scene.friction': expected a number"),
        ("scene.frict=0.5", "unknown key 'frict' in 'scene'"),
        ("machine.search.pattern=zigzag", "key 'machine.search.pattern'"),
        ("loop.rate_hz=-5", "key 'loop.rate_hz'"),
    ],
)
def test_a_bad_override_is_one_line_and_exit_2(override, message, tmp_path, capsys):
    code = main(["--task", "usb_c", "--set", override, "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


def test_a_bad_task_file_is_one_line_and_exit_2(tmp_path, capsys):
    bad = tmp_path / "task.yaml"  # a user's task on the shipped base, with one bad value
    base = CONFIG_ROOT / "tasks" / "base" / "usb.yaml"
    text = load_task("usb_c").path.read_text().replace("extends: base/usb.yaml", f"extends: {base}")
    bad.write_text(text + "loop:\n  rate_hz: fast\n")
    code = main(["--task", str(bad), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2 and "key 'loop.rate_hz'" in err and len(err.strip().splitlines()) == 1
    code = main(["--task", "usb_z", "--out", str(tmp_path / "out")])
    assert code == 2 and "unknown task configuration 'usb_z'" in capsys.readouterr().err


def test_the_oracle_is_refused_on_the_robot(tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(["--task", "usb_c", "--backend", "real", "--controller", "oracle",
              "--out", str(tmp_path / "o")])  # fmt: skip
    assert exit_info.value.code == 2 and "sim only" in capsys.readouterr().err
    with pytest.raises(ConfigError, match="sim only"):
        trial.run(load_task("usb_c"), "oracle", 0, backend="real")


def test_the_controller_never_reads_the_truth(monkeypatch, tmp_path):
    """While the loop runs, nothing reads the scene's truth (except the labelled oracle)."""
    reads: list[str] = []
    running = {"now": False}
    original_run = ControlLoop.run

    def run_and_mark(self, *args, **kwargs):
        running["now"] = True
        try:
            return original_run(self, *args, **kwargs)
        finally:
            running["now"] = False

    def spy(name, original):
        def wrapped(self, *args, **kwargs):
            if running["now"]:
                reads.append(name)
            return original(self, *args, **kwargs)

        return wrapped

    monkeypatch.setattr(ControlLoop, "run", run_and_mark)
    monkeypatch.setattr(TruthLog, "arrays", spy("arrays", TruthLog.arrays))
    outcome = trial.run(load_task("usb_c", SHORT), "dipole", 3, out_dir=tmp_path / "d")
    assert outcome.truth is not None and len(outcome.truth["t_s"]) > 100
    assert reads == []
    monkeypatch.setattr(TrueWrench, "__call__", spy("true_wrench", TrueWrench.__call__))
    trial.run(load_task("usb_c", SHORT), "oracle", 3)
    assert reads  # the oracle does read the truth: the spy works


def test_a_short_trial_writes_its_record(tmp_path):
    out = tmp_path / "trial"
    code = main(["--task", "usb_c", "--seed", "2", "--out", str(out), *sum(
        (["--set", s] for s in SHORT), [])])  # fmt: skip
    assert code == 0
    ticks = [json.loads(line) for line in (out / "ticks.jsonl").read_text().splitlines()]
    assert len(ticks) > 500 and ticks[0]["phase"] == "grasp"
    transitions = (out / "transitions.jsonl").read_text().splitlines()
    assert json.loads(transitions[0])["from"] == "grasp"
    summary = json.loads((out / "trial.json").read_text())
    assert summary["seed"] == 2 and summary["config"]["touch_spiral"]["timeout_s"] == 6.0
    truth = np.load(out / "truth.npz")
    assert np.isfinite(truth["depth_m"]).all() and (out / "summary.png").stat().st_size > 10000
    code = main(["--task", "usb_c", "--out", str(out)])  # never over an earlier record
    assert code == 2


@pytest.mark.parametrize(
    ("name", "raised"), [("SIGINT", KeyboardInterrupt), ("SIGTERM", Terminated)]
)
def test_a_signal_that_stopped_a_batch_trial_stops_the_batch(monkeypatch, name, raised):
    loop = types.SimpleNamespace(reason="signal", message=name)
    outcome = types.SimpleNamespace(loop=loop, result="never recorded")
    monkeypatch.setattr(trial, "run", lambda *args, **kwargs: outcome)
    with pytest.raises(raised):
        trial.run_trial(TrialSpec("usb_c", "dipole", 0))


def test_a_real_run_without_hardware_names_every_device_in_one_line(tmp_path):
    """No robot at the arm's address, no gripper, camera or pad: exit 1, one line naming
    each device and what to check, no traceback, and no record left behind."""
    arm = tmp_path / "arm.yaml"
    arm.write_text((CONFIG_ROOT / "robot" / "xarm6.yaml").read_text().replace(
        "ip: 192.168.1.185", "ip: 127.0.0.1"))  # fmt: skip
    out = tmp_path / "run"
    ran = subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "run_trial.py"), "--task", "usb_c",
         "--backend", "real", "--set", f"devices.arm={arm}", "--out", str(out)],
        capture_output=True, text=True, timeout=120, env=dict(os.environ, MPLBACKEND="Agg"),
    )  # fmt: skip
    errors = [line for line in ran.stderr.splitlines() if line.startswith("run_trial:")]
    assert ran.returncode == 1 and "Traceback" not in ran.stderr
    assert len(errors) == 1 and errors[0].startswith("run_trial: error: arm, gripper, tactile")
    for role in ("arm: xarm6: ", "gripper: hande: ", "tactile: ", "gamepad: "):
        assert f"; {role}" in errors[0] or f"not ready: {role}" in errors[0]
    assert not out.exists() or not any(out.iterdir())


def test_a_trial_that_ends_in_a_fault_says_so_in_its_exit_code(tmp_path, capsys):
    out = tmp_path / "trial"
    code = main(["--task", "usb_c", "--set", "loop.tactile_max_age_s=0.001", "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 1 and err.count("\n") == 1, err
    assert err.startswith("run_trial: error: the run ended in a fault (safe stop done): stale")
    assert (out / "trial.json").is_file()  # the record is kept, complete


@pytest.mark.parametrize(
    ("depth_mm", "expected"),
    [
        ([0, 2, 5, 6, 6.5], 2),  # in once, to the end
        ([0, 5.5, 6, 1, 0, 5, 6.5], 5),  # in, pulled out, in again: the last arrival
        ([0, 5, 6, 6.5, 3], None),  # in, then out at the end: not inserted
        ([0, 1, 4.9], None),  # never at the depth
        ([5, 5, 5], 0),
        ([], None),
    ],
)
def test_the_insertion_counts_from_the_plugs_last_arrival_at_the_depth(depth_mm, expected):
    assert trial.final_insertion(np.array(depth_mm, float) * 1e-3, 0.005) == expected
