"""Fault injection for the tactile camera: a truncated and a corrupted MJPG video as its
stream (raw mode: the driver decodes each JPEG itself, as on V4L2)."""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import pytest

from core.errors import DeviceNotConnectedError
from drivers.tactile import TactileCamera
from tests.drivers.test_camera import (
    DIGIT_ID,
    by_id_dir,
    digit_config,
    paced_factory,
    raises_now,
    textured,
    wait_for,
)
from tests.video_faults import corrupt_frame, truncate_inside_frame, write_mjpg

FRAMES = 12


@pytest.fixture
def clip(tmp_path: Path) -> Path:
    return write_mjpg(tmp_path / "clip.avi", [textured(240, 320, seed=i) for i in range(FRAMES)])


def test_truncated_video_warns_keeps_good_frames_then_disconnects(tmp_path, clip, caplog):
    truncate_inside_frame(clip, 7)  # frames 0-6 intact, frame 7 cut, 8-11 gone
    factory, _ = paced_factory(raw=True, rate_hz=100, loop=False)
    camera = TactileCamera(digit_config(by_id_dir(tmp_path, DIGIT_ID, clip)), factory)
    with caplog.at_level(logging.WARNING, logger="drivers.tactile.camera"):
        camera.connect()
        first = camera.read_latest(max_age_s=1.0)
        wait_for(lambda: raises_now(camera, DeviceNotConnectedError))
    assert first.image.shape == (320, 240, 3)
    warnings = [r.getMessage() for r in caplog.records if "did not decode" in r.getMessage()]
    assert len(warnings) == 1, warnings  # the cut frame, reported once
    camera.disconnect()


def test_corrupted_frame_is_skipped_with_one_warning_and_the_stream_goes_on(tmp_path, clip, caplog):
    corrupt_frame(clip, 5)
    factory, _ = paced_factory(raw=True, rate_hz=200, loop=True)
    camera = TactileCamera(digit_config(by_id_dir(tmp_path, DIGIT_ID, clip)), factory)
    seen = []
    with caplog.at_level(logging.WARNING, logger="drivers.tactile.camera"), camera:
        wait_for(lambda: any("did not decode" in r.getMessage() for r in caplog.records))
        for _ in range(30):  # past the bad frame, and round the loop again
            frame = camera.read_latest(max_age_s=1.0)
            seen.append(frame.image.copy())
            wait_for(lambda f=frame: camera.read_latest(1.0).t_s > f.t_s)
        assert camera.is_connected
    distinct = {image.tobytes() for image in seen}
    assert len(distinct) >= FRAMES // 2
    assert not any(np.array_equal(image, np.zeros_like(image)) for image in seen)
