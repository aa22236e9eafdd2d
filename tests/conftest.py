"""What the whole suite shares: one recorded trial, made once per test run and shared by
the pytest-xdist workers through a file lock in the run's common temporary folder."""

from __future__ import annotations

from pathlib import Path

import pytest
from filelock import FileLock

from controller.episode.session import EPISODE_FILE, EpisodeOptions
from controller.run import load_task
from evaluation.trials.trial import run

RECORDED_TASK, RECORDED_CONTROLLER, RECORDED_SEED = "usb_c", "dipole", 0
_DONE = "recorded.done"


@pytest.fixture(scope="session")
def run_root(tmp_path_factory, worker_id) -> Path:
    """The temporary folder common to every worker of this test run (each worker's own
    ``tmp_path_factory`` base lies in it; without xdist, that base itself)."""
    base = tmp_path_factory.getbasetemp()
    return base if worker_id == "master" else base.parent


@pytest.fixture(scope="session")
def recorded_trial(run_root) -> Path:
    """The record folder of a simulated USB-C trial (seed 0, the dipole controller) that
    inserted, with its episode recorded with lossless (PNG) frames and made read-only (the
    tools never write over their input): ``trial.json``, ``ticks.jsonl``,
    ``transitions.jsonl``, ``truth.npz``, ``episode.mcap``. Only the tests read it."""
    folder = run_root / "recorded_trial"
    with FileLock(str(run_root / "recorded_trial.lock")):
        if not (run_root / _DONE).exists():
            episode = EpisodeOptions(image_format="png")
            task = load_task(RECORDED_TASK)
            outcome = run(task, RECORDED_CONTROLLER, RECORDED_SEED, out_dir=folder,
                          episode=episode)  # fmt: skip
            assert outcome.result.success
            (folder / EPISODE_FILE).chmod(0o444)
            (run_root / _DONE).touch()
    return folder
