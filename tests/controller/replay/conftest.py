"""The replay tools' tests read the suite's recorded trial (tests/conftest.py)."""

from __future__ import annotations

from pathlib import Path

import pytest

from controller.episode.session import EPISODE_FILE


@pytest.fixture(scope="session")
def episode_path(recorded_trial) -> Path:
    """The recorded trial's episode: USB-C, seed 0, dipole, lossless frames, read-only."""
    return recorded_trial / EPISODE_FILE
