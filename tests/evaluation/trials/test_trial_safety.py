"""Whole simulated trials: one per task succeeds on a fixed seed; an operator takes over and
hands back through the scripted gamepad; a driver fault mid-insertion and SIGTERM end in a
safe stop."""

import dataclasses
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from controller.episode import read_episode
from controller.insertion import Phase
from controller.run import CONTROLLERS, Controller, run_task
from controller.run.task import load_task
from drivers.sim.twins.gamepad import PadEvent
from evaluation.trials import trial

ROOT = Path(__file__).resolve().parents[3]
PERIOD_S = 0.01  # the tasks' loop.rate_hz is 100


@pytest.mark.parametrize(("task", "seed"), [("usb_c", 3), ("usb_a", 0)])
def test_a_short_trial_per_task_succeeds_on_a_fixed_seed(task, seed, easy_task):
    # the easy scene (tests/easy_scene.py): this checks the trial's path and scoring; the
    # machine's success on the drawn scene is the insertion trials' to measure
    outcome = trial.run(easy_task(task), "dipole", seed)
    assert outcome.result.success, outcome.transitions
    # time to insert counts from the controller's first tick, after the devices' start-up,
    # to the plug's last arrival at the depth (here its only one)
    required = load_task(task).config.machine.insert.depth_m
    at_depth = outcome.truth["depth_m"] >= required
    assert at_depth[-1] and np.count_nonzero(at_depth[1:] & ~at_depth[:-1]) == 1
    reached_s = outcome.truth["t_s"][at_depth][0]
    started_s = outcome.loop.stats.first_tick_s
    assert started_s > 0.0  # the gripper's activation came first
    assert outcome.result.time_to_insert_s == pytest.approx(reached_s - started_s)
    assert outcome.result.max_wrist_force_n < outcome.result.force_limit_n
    assert outcome.transitions[-1].target is Phase.DONE


def test_a_driver_fault_mid_insertion_stops_safely_within_one_period(easy_task):
    built, stops, injected = [], [], []

    def spy_on_stops(device_set):
        """The built arm notes each ``stop()`` time (on the scene's clock)."""
        arm = device_set.devices.arm
        arm_stop = arm.stop

        def stop():
            stops.append(device_set.clock.now())
            arm_stop()

        arm.stop = stop
        built.append(device_set)

    class FaultingMachine:
        """The task's machine; the arm faults on the first tick of INSERT."""

        def __init__(self, inner):
            self._inner = inner

        def __getattr__(self, name):
            return getattr(self._inner, name)

        def step(self, observation):
            command = self._inner.step(observation)
            if self._inner.phase is Phase.INSERT and not injected:
                built[0].devices.arm.inject_fault(21, "simulated joint overcurrent")
                injected.append(built[0].clock.now())
            return command

    dipole = CONTROLLERS["dipole"]
    faulting = Controller(lambda config: FaultingMachine(dipole.machine(config)),
                          dipole.wrench_source)  # fmt: skip
    outcome = run_task(
        easy_task("usb_c"),  # the machine must reach INSERT
        "faulting",
        3,
        controllers={"faulting": faulting},
        prepare=spy_on_stops,
    )
    assert injected, "the run never reached INSERT"
    assert outcome.loop.reason == "fault" and "code 21" in outcome.loop.message
    assert outcome.machine.phase is Phase.FAILED
    assert len(stops) == 1 and 0.0 <= stops[0] - injected[0] <= PERIOD_S + 1e-9
    assert outcome.transitions[-1].reason == "device_fault"


def test_an_operator_takes_over_and_hands_back_through_the_gamepad(easy_task):
    task = easy_task("usb_c")  # the hand-back must still lead to an insertion
    script = [
        PadEvent(1.5, axes={"vz": 0.5}, buttons={"deadman": True}),  # during GRASP (settling)
        PadEvent(2.5, axes={"vz": 0.0}),
        PadEvent(3.5, buttons={"hand_back": True}),
        PadEvent(3.6, buttons={"hand_back": False}),
    ]
    play = lambda built: built.devices.gamepad.play(script)  # noqa: E731
    outcome = trial.run(task, "dipole", 12, prepare=play)
    reasons = [(t.source, t.target, t.reason) for t in outcome.transitions]
    takeover = next(t for t in outcome.transitions if t.reason == "operator_takeover")
    back = next(t for t in outcome.transitions if t.reason == "hand_back")
    assert takeover.source is Phase.GRASP and 1.5 <= takeover.t_s <= 1.5 + 2 * PERIOD_S
    assert 3.5 <= back.t_s <= 3.5 + 2 * PERIOD_S
    assert back.target is Phase.GRASP  # the plug not yet released: grasp again
    assert outcome.result.success, reasons
    truth = outcome.truth
    during = (truth["t_s"] > 1.6) & (truth["t_s"] < 2.5)
    rise = np.diff(truth["tip_xyz_b"][during, 2])
    assert rise.sum() > 0.005  # the operator lifted the plug (0.5 of 0.02 m/s for ~0.9 s)


def test_sigterm_during_a_trial_stops_safely_and_keeps_the_record(tmp_path):
    out = tmp_path / "trial"
    env = dict(os.environ, MPLBACKEND="Agg")
    process = subprocess.Popen(
        [sys.executable, str(ROOT / "scripts" / "run_trial.py"), "--task", "usb_c",
         "--seed", "9", "--out", str(out), "--realtime"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env, cwd=tmp_path,
    )  # fmt: skip
    ticks_file, deadline = out / "ticks.jsonl", time.monotonic() + 120.0
    while time.monotonic() < deadline:  # the loop has run (its handlers are installed)
        if ticks_file.exists() and ticks_file.read_text().count("\n") >= 50:
            break
        time.sleep(0.1)
    process.send_signal(signal.SIGTERM)
    stdout, stderr = process.communicate(timeout=60)
    assert process.returncode == 143, stderr
    assert stderr.startswith("run_trial: ended by SIGTERM (safe stop done)"), stderr
    assert stderr.count("\n") == 1 and "Traceback" not in stderr
    summary = json.loads((out / "trial.json").read_text())
    assert summary["loop"]["reason"] == "signal"
    assert not summary["result"]["success"]
    ticks = (out / "ticks.jsonl").read_text().splitlines()
    assert ticks and all(json.loads(line) for line in ticks)  # every line whole
    episode = read_episode(out / "episode.mcap")  # closed on SIGTERM, with its outcome
    assert episode.complete and episode.outcome["reason"] == "signal"
    assert episode.counts["/loop/tick"] == len(ticks)


def test_a_wrong_size_frame_mid_trial_ends_as_a_fault_with_a_complete_record(tmp_path):
    """Fault injection: from 3 s on the camera delivers frames of the wrong size, so the
    estimator raises ValueError inside a tick. The trial stops safely, the machine records
    FAILED, and trial.json is written and says why."""

    def shrink_frames_after_3_s(built):
        read = built.devices.tactile.read_latest

        def read_latest(max_age_s):
            frame = read(max_age_s)
            if frame.t_s < 3.0:
                return frame
            return dataclasses.replace(frame, image=frame.image[::2, ::2])

        built.devices.tactile.read_latest = read_latest

    out = tmp_path / "trial"
    outcome = trial.run(load_task("usb_c"), "dipole", 9, out_dir=out,
                        prepare=shrink_frames_after_3_s)  # fmt: skip
    assert outcome.loop.reason == "fault"
    assert outcome.loop.message.startswith("the tick raised ValueError")
    assert outcome.transitions[-1].target is Phase.FAILED
    summary = json.loads((out / "trial.json").read_text())
    assert summary["loop"]["reason"] == "fault" and "ValueError" in summary["loop"]["message"]
    assert summary["result"]["status"] == "failed"
    assert summary["result"]["failure_reason"] == "device_fault"
    last = json.loads((out / "ticks.jsonl").read_text().splitlines()[-1])
    assert last["fault"] == outcome.loop.message and 2.9 <= last["t_s"] <= 3.1
