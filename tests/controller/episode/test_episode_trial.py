"""An episode written by a real simulated trial: every stream round-trips, the losslessly
recorded frames re-estimate the logged estimates exactly, and a trial killed with SIGKILL
leaves a file the reader opens up to its last flush and ``repair`` finishes."""

from __future__ import annotations

import bisect
import itertools
import json
import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml
from mcap.reader import make_reader

from controller.episode import TOPICS, decode_image, grid_arrays, read_episode
from controller.episode.repair import repair
from controller.episode.session import EPISODE_FILE
from controller.run import load_task
from controller.tactile import estimator_for_sensor
from controller.tactile.calibration import Calibration
from controller.tactile.wrench import VALUE_FIELDS
from tests.conftest import RECORDED_SEED, RECORDED_TASK

ROOT = Path(__file__).resolve().parents[3]


@pytest.fixture(scope="module")
def trial(recorded_trial):
    """The suite's recorded trial (tests/conftest.py): its task and record folder."""
    return load_task(RECORDED_TASK), recorded_trial


def test_every_stream_round_trips(trial):
    task, out = trial
    record = json.loads((out / "trial.json").read_text())
    transitions_record = [json.loads(line) for line in
                          (out / "transitions.jsonl").read_text().splitlines()]  # fmt: skip
    truth_record = np.load(out / "truth.npz")
    ep = read_episode(out / EPISODE_FILE)
    assert ep.complete and ep.finished and ep.read_bytes == ep.size_bytes
    # nothing dropped
    assert set(TOPICS) - set(ep.counts) == {"/episode/drops"}
    assert ep.info["seed"] == str(RECORDED_SEED) and ep.info["controller"] == "dipole"
    assert ep.info["tactile_image_format"] == "png"
    assert json.loads(ep.outcome["result"])["success"] == record["result"]["success"]
    assert ep.outcome["dropped_total"] == "0"
    assert b"task: usb_c" in ep.attachments["task.yaml"]

    ticks = [json.loads(line) for line in (out / "ticks.jsonl").read_text().splitlines()]
    arm = [m.value for m in ep.messages("/arm/status")]
    assert len(arm) == len(ticks) == ep.counts["/loop/tick"] == ep.counts["/control/command"]
    assert [a["tcp_xyz_m"] for a in arm] == [t["tcp_xyz_m"] for t in ticks]
    phases = [m.value["phase"] for m in ep.messages("/loop/tick")]
    assert phases == [t["phase"] for t in ticks]
    commands = [m.value for m in ep.messages("/control/command")]
    assert [c["limited"] for c in commands] == [t["limited"] for t in ticks]
    assert [c["rule"] for c in commands] == [t["rule"] for t in ticks]
    assert "search.sweep" in {c["rule"] for c in commands}
    twists = [
        c["twist_linear_m_s"] + c["twist_angular_rad_s"] for c in commands if c["twist_linear_m_s"]
    ]
    assert twists == [t["twist"] for t in ticks if "twist" in t]
    gripper = list(ep.messages("/gripper/status"))  # latched: a tick holds the newest before
    tick_times = [m.t_s for m in ep.messages("/loop/tick")]
    assert gripper[0].t_s == tick_times[0] and len(gripper) < len(ticks)
    period_s = 1.0 / task.config.loop.rate_hz  # a tick 1 s or more after the last one
    assert all(b.t_s - a.t_s < 1.0 + 1.5 * period_s for a, b in itertools.pairwise(gripper))
    times = [g.t_s for g in gripper]
    held = [gripper[bisect.bisect_right(times, t) - 1] for t in tick_times]
    assert [g.value["width_m"] for g in held] == [t["gripper_width_m"] for t in ticks]
    teleop = list(ep.messages("/teleop/input"))
    assert 0 < len(teleop) < len(ticks)
    assert all(m.value["in_control_by"] == "machine" for m in teleop)

    transitions = [m.value for m in ep.messages("/machine/transition")]
    assert [(t["from"], t["to"], t["reason"], t["rule"]) for t in transitions] == [
        (t["from"], t["to"], t["reason"], t["rule"]) for t in transitions_record
    ] and transitions

    tf = [m.value.transforms[0] for m in ep.messages("/tf")]
    assert (tf[0].parent_frame_id, tf[0].child_frame_id) == ("B", "T")
    assert math.isclose(tf[-1].translation.z, arm[-1]["tcp_xyz_m"][2])
    q = tf[-1].rotation
    assert math.isclose(q.x**2 + q.y**2 + q.z**2 + q.w**2, 1.0, rel_tol=1e-9)

    wrenches = [m.value for m in ep.messages("/tactile/wrench")]
    estimates = [t["estimate"] for t in ticks if "estimate" in t]
    logged = {w["t_s"]: [w[k] for k in VALUE_FIELDS] for w in wrenches}
    assert all(logged[t["estimate_t_s"]] == [t["estimate"][k] for k in VALUE_FIELDS]
               for t in ticks if "estimate" in t)  # fmt: skip
    assert estimates and len(wrenches) == ep.counts["/tactile/image"]

    image = decode_image(next(ep.messages("/tactile/image")).value)
    assert image.dtype == np.uint8 and image.shape == (240, 320, 3)
    grid = grid_arrays(next(ep.messages("/tactile/field")).value)
    assert grid["u_mm"].shape == (12, 16) and np.isfinite(grid["div"]).all()

    truth = [m.value for m in ep.messages("/sim/truth")]
    assert len(truth) == len(truth_record["t_s"])
    assert np.allclose([r["depth_m"] for r in truth], truth_record["depth_m"])
    hole = [m.value.transforms[1] for m in ep.messages("/sim/tf")][-1]
    assert hole.child_frame_id == "H"


def test_lossless_frames_re_estimate_the_logged_estimates_exactly(trial):
    task, out = trial
    ep = read_episode(out / EPISODE_FILE)
    attached = yaml.safe_load(ep.attachments["calibration.yaml"])
    calibration = Calibration.from_document(attached, "calibration.yaml")
    assert calibration == task.calibration  # the run's, applied to every logged estimate
    estimator = estimator_for_sensor(task.tactile_model, task.config.estimator, calibration)
    images = ep.messages("/tactile/image")
    again = []
    for m in ep.messages("/tactile/push"):
        call = m.value
        if call["call"] == "push":
            frame = decode_image(next(images).value)
            again.append(estimator.push(frame, call["frame_t_s"]))
        elif call["call"] == "rezero":
            estimator.rezero(call["n_frames"])
        else:
            estimator.capture_open(call["n_frames"])
    logged = [m.value for m in ep.messages("/tactile/wrench")]
    assert len(again) == len(logged)
    for e, w in zip(again, logged, strict=True):
        assert [getattr(e, k) for k in VALUE_FIELDS] == [w[k] for k in VALUE_FIELDS]
        assert e.zeroing == w["zeroing"] and e.contact == w["contact"]
    assert any(not w["zeroing"] and w["tau_x"] != 0.0 for w in logged)


def test_sigkill_leaves_a_file_read_to_its_last_flush_and_repair_finishes_it(tmp_path):
    out = tmp_path / "trial"
    process = subprocess.Popen(
        [sys.executable, str(ROOT / "scripts" / "run_trial.py"), "--task", "usb_c",
         "--seed", "1", "--out", str(out)],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, cwd=tmp_path,
        env=dict(os.environ, MPLBACKEND="Agg"),
    )  # fmt: skip
    episode = out / EPISODE_FILE
    deadline = time.monotonic() + 120.0
    while time.monotonic() < deadline and process.poll() is None:
        if episode.exists() and episode.stat().st_size > 400_000:  # the loop has run
            break
        time.sleep(0.05)
    assert process.poll() is None, "the trial ended before it could be killed"
    process.send_signal(signal.SIGKILL)
    process.wait(timeout=30)

    ep = read_episode(episode)
    assert not ep.finished and not ep.complete and ep.outcome is None
    assert 0 < ep.read_bytes <= ep.size_bytes
    assert ep.counts["/loop/tick"] > 10 and ep.counts["/tactile/image"] > 2
    ticks = [m.value["index"] for m in ep.messages("/loop/tick")]
    assert ticks == list(range(len(ticks)))  # no hole up to the last flush

    fixed = tmp_path / "repaired.mcap"
    report = repair(episode, fixed)
    assert report.messages == sum(ep.counts.values())
    again = read_episode(fixed)
    assert again.finished and not again.complete
    assert again.metadata["repair"]["complete"] == "false"
    assert again.counts == ep.counts and again.info == ep.info
    with fixed.open("rb") as handle:  # the summary a seeking reader (Foxglove's) needs
        summary = make_reader(handle).get_summary()
    assert summary is not None and summary.statistics.message_count == report.messages
