"""The batch tests' trial functions (``--trial-function``) and their ``check_spec``: a worker
process (the local pool, Ray, a batch started as a command) imports this small module by
name, not a test module with everything it imports."""

from __future__ import annotations

import math
import os
import time
from pathlib import Path
from typing import TYPE_CHECKING

from controller.run.result import TrialResult
from core.config import ConfigError

if TYPE_CHECKING:
    from evaluation.trials.spec import TrialSpec

FORCE_LIMIT_N = 20.0
PIDS = "BATCH_STOP_TEST_PIDS"  # the folder where each long trial notes its process id


def check_spec(spec: TrialSpec) -> None:
    """The check of this module's trial functions: only usb_a and usb_c, only known override
    keys."""
    if spec.task not in ("usb_a", "usb_c"):
        raise ConfigError(f"unknown task configuration {spec.task!r}")
    for item in spec.overrides:
        if item.partition("=")[0] not in ("machine.insert.speed_m_s", "scene.friction"):
            raise ConfigError(f"override {item!r}: unknown key")


def fake_trial(spec: TrialSpec) -> TrialResult:
    """Deterministic: seeds 3, 7, 11, ... time out; seed 5 raises; the rest succeed;
    ``align`` estimates the plug in the hand (its FEEL, the width plane) 0.001 rad and 0.1 mm
    off per seed, ``dipole`` the thickness plane (-0.001 rad, -0.1 mm; none on seed 2)."""
    if spec.seed == 5:
        raise RuntimeError("boom\nsecond line")
    success = spec.seed % 4 != 3
    speed = 1.0
    for item in spec.overrides:
        key, _, value = item.partition("=")
        if key == "machine.insert.speed_m_s":
            speed = float(value)
    time_s = 5.0 + 0.5 * spec.seed / speed
    return TrialResult(
        task=spec.task,
        controller=spec.controller,
        seed=spec.seed,
        success=success,
        status="inserted" if success else "failed",
        failure_reason=None if success else "timeout",
        time_to_insert_s=time_s if success else None,
        duration_s=time_s + 1.0,
        max_wrist_force_n=10.0 + spec.seed,
        force_limit_n=FORCE_LIMIT_N,
        wall_time_s=0.25,
        **_FAKE_POSES.get(spec.controller, lambda seed: {})(spec.seed),
    )


def _fake_pose(seed: int) -> dict[str, float]:
    return {
        "grasp_tilt_est_rad": 0.02 + 0.001 * seed,
        "grasp_tilt_true_rad": 0.02,
        "tip_x_est_m": 1e-4 * seed,
        "tip_x_true_m": 0.0,
        "grasp_tilt_thickness_true_rad": 0.01,
        "tip_y_true_m": 0.0,
    }


def _fake_thickness_pose(seed: int) -> dict[str, float]:
    """The press spiral's estimate: the thickness plane only, none on seed 2."""
    return {
        "grasp_tilt_thickness_est_rad": math.nan if seed == 2 else 0.01 - 0.001 * seed,
        "grasp_tilt_thickness_true_rad": 0.01,
        "tip_y_est_m": math.nan if seed == 2 else -1e-4 * seed,
        "tip_y_true_m": 0.0,
        "grasp_tilt_true_rad": 0.02,
        "tip_x_true_m": 0.0,
    }


_FAKE_POSES = {"align": _fake_pose, "dipole": _fake_thickness_pose}


def slow_trial(spec: TrialSpec) -> TrialResult:
    """Seed 0 returns at once, the others take long (to interrupt)."""
    if spec.seed > 0:
        time.sleep(30)
    return fake_trial(spec)


def recording_trial(spec: TrialSpec) -> TrialResult:
    """Writes the spec into its out_dir, as the real trial writes its record."""
    spec.out_dir.mkdir(parents=True)
    (spec.out_dir / "spec.txt").write_text(repr(spec))
    return fake_trial(spec)


def long_trial(spec: TrialSpec) -> TrialResult:
    """Notes its process id and writes its record; seed 0 then returns, the others run on
    for a minute (to be stopped)."""
    (Path(os.environ[PIDS]) / f"{spec.seed}-{os.getpid()}").touch()
    if spec.out_dir is not None:
        spec.out_dir.mkdir(parents=True)
        (spec.out_dir / "trial.json").write_text("{}")
    if spec.seed > 0:
        time.sleep(60)
    return _inserted(spec)


def _inserted(spec: TrialSpec) -> TrialResult:
    return TrialResult(spec.task, spec.controller, spec.seed, True, "inserted", None, 1.0, 2.0,
                       1.0, 20.0, 0.1)  # fmt: skip


def interrupted_at_seed_3(spec: TrialSpec) -> TrialResult:
    """Seeds 0-2 succeed at once; seed 3 is a Ctrl-C."""
    if spec.seed == 3:
        raise KeyboardInterrupt
    return _inserted(spec)
