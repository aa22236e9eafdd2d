"""One real recorded episode for the replay tools' tests: a simulated USB-C trial (seed 0,
the dipole controller) recorded once per session with lossless (PNG) frames."""

from __future__ import annotations

from pathlib import Path

import pytest

from controller.episode.session import EpisodeOptions, EpisodeRecording
from controller.run import load_task
from evaluation.trials.trial import run


@pytest.fixture(scope="session")
def episode_path(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("episode") / "episode.mcap"
    task = load_task("usb_c")
    recording = EpisodeRecording.open(
        path,
        task.raw,
        task=task.config.task,
        task_file=task.path,
        overrides=(),
        seed=0,
        controller="dipole",
        backend="sim",
        options=EpisodeOptions(image_format="png"),
    )
    try:
        outcome = run(task, "dipole", 0, episode=recording)
    finally:
        recording.close({"reason": "done"})
    assert outcome.result.success
    path.chmod(0o444)  # the tools never write over their input
    return path
