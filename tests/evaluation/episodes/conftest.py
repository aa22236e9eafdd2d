"""One real recorded episode for the replay tools' tests: a simulated USB-C trial (seed 0,
the dipole controller) recorded once per session with lossless (PNG) frames."""

from __future__ import annotations

from pathlib import Path

import pytest

from controller.episode.session import EPISODE_FILE, EpisodeOptions
from controller.run import load_task
from evaluation.trials.trial import run


@pytest.fixture(scope="session")
def episode_path(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("trial")
    episode = EpisodeOptions(image_format="png")
    outcome = run(load_task("usb_c"), "dipole", 0, out_dir=folder, episode=episode)
    assert outcome.result.success
    path = folder / EPISODE_FILE
    path.chmod(0o444)  # the tools never write over their input
    return path
