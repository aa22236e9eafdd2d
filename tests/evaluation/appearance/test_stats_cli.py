"""The appearance statistics tool as a user runs it: python -m evaluation gel_stats ..."""

import json
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from drivers.sim.render.gel_renderer import GelRenderer
from drivers.sim.render.real_texture import REAL_GELS_DIR
from evaluation.appearance.stats_cli import main

ROOT = Path(__file__).resolve().parents[3]


@pytest.fixture(scope="module")
def frames():
    renderer = GelRenderer(rng=np.random.default_rng(1), appearance="realistic")
    return [renderer.render(np.full((48, 64, 2), 0.5 * k, np.float32)) for k in range(3)]


def test_images_folders_and_videos_to_json(frames, tmp_path, capsys):
    folder = tmp_path / "frames"
    folder.mkdir()
    for index, frame in enumerate(frames):
        cv2.imwrite(str(folder / f"f{index}.png"), frame)
    video = tmp_path / "clip.avi"
    writer = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"MJPG"), 25, (320, 240))
    for frame in frames:
        writer.write(frame)
    writer.release()
    portrait = REAL_GELS_DIR / "digit_background_b.jpg"
    out = tmp_path / "stats.json"
    args = [str(folder / "f0.png"), str(folder), str(video), str(portrait), "--json", str(out)]
    assert main(args) == 0
    table = capsys.readouterr().out
    assert table.startswith("| statistic |") and "| marker diameter px |" in table
    document = json.loads(out.read_text())
    assert [document[str(p)]["frames"] for p in (folder / "f0.png", folder, video)] == [1, 3, 3]
    image = document[str(folder / "f0.png")]["stats"]
    assert document[str(folder)]["per_frame"][0] == image
    assert image["marker_count"] > 50 and image["band_rms_grey"]["2-6px"] < 2.0
    clip = document[str(video)]["stats"]  # MJPEG keeps the look
    assert clip["marker_diameter_px"] == pytest.approx(image["marker_diameter_px"], abs=0.3)
    digit = document[str(portrait)]["stats"]
    assert (digit["width_px"], digit["height_px"]) == (320, 240)  # turned to the working size
    assert digit["marker_count"] == 0 and digit["marker_diameter_px"] is None


def test_native_size_and_every_kth_frame(frames, tmp_path):
    folder = tmp_path / "frames"
    folder.mkdir()
    for index, frame in enumerate(frames):
        cv2.imwrite(str(folder / f"f{index}.png"), cv2.resize(frame, (400, 300)))
    out = tmp_path / "s.json"
    assert main([str(folder), "--size", "native", "--every", "2", "--json", str(out)]) == 0
    entry = json.loads(out.read_text())[str(folder)]
    assert entry["frames"] == 2 and entry["stats"]["width_px"] == 400


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["missing.png"], "does not exist"),
        (["{empty}"], "holds no images"),
        (["{bad}"], "cannot read image"),
        ([str(REAL_GELS_DIR / "gelsight_background.png"), "--size", "12x9"], "--size"),
        ([str(REAL_GELS_DIR / "gelsight_background.png"), "--every", "0"], "--every"),
    ],
)
def test_bad_input_is_one_line_and_exit_code_2(tmp_path, capsys, args, message):
    empty = tmp_path / "empty"
    empty.mkdir()
    bad = tmp_path / "bad.png"
    bad.write_bytes(b"not a png")
    assert main([a.format(empty=empty, bad=bad) for a in args]) == 2
    err = capsys.readouterr().err
    assert err.startswith("gel_stats: error:") and err.count("\n") == 1 and message in err


def test_the_script_runs_as_a_user_runs_it(tmp_path):
    capture = REAL_GELS_DIR / "gelsight_markers_a.png"
    result = subprocess.run(
        [sys.executable, "-m", "evaluation", "gel_stats", str(capture)],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    assert result.returncode == 0 and "| marker diameter px | 11.6 |" in result.stdout
