"""The offline estimator as a user runs it: python scripts/estimate.py ..."""

import csv
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from drivers.sim.render.marker_images import MarkerImageRenderer
from drivers.sim.scenes.synthetic_sequence import phase_patterns
from evaluation.offline.estimate_cli import CSV_COLUMNS, main

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def frames():
    renderer = MarkerImageRenderer(rng=np.random.default_rng(5))
    tilt = phase_patterns((240, 320))["tilt_x"]
    return [renderer.render(a * tilt) for a in (0.0, 0.0, 0.5, 1.0, -1.0, 0.0)]


@pytest.fixture
def folder(tmp_path, frames):
    path = tmp_path / "frames"
    path.mkdir()
    for i, frame in enumerate(frames):  # names that sort wrongly as plain strings
        cv2.imwrite(str(path / f"f{i * 5}.png"), frame)
    return path


def read_rows(path):
    with path.open() as handle:
        return list(csv.DictReader(handle))


def test_folder_to_csv(folder, tmp_path, capsys):
    out = tmp_path / "out.csv"
    assert main([str(folder), "--reference", "0:2", "--out", str(out)]) == 0
    rows = read_rows(out)
    assert tuple(rows[0]) == CSV_COLUMNS
    assert len(rows) == 6
    tau_x = [float(r["tau_x"]) for r in rows]
    assert tau_x[3] > tau_x[2] > 0 > tau_x[4]  # natural sort kept f10 after f5
    assert float(rows[1]["time_s"]) == pytest.approx(1 / 25)  # sensor profile's 25 fps


def test_video_to_csv_with_fps(frames, tmp_path):
    video = tmp_path / "clip.avi"
    writer = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"MJPG"), 30, (320, 240))
    for frame in frames:
        writer.write(frame)
    writer.release()
    out = tmp_path / "v.csv"
    assert main([str(video), "--out", str(out), "--fps", "10", "--method", "paper"]) == 0
    rows = read_rows(out)
    assert len(rows) == 6 and float(rows[2]["time_s"]) == pytest.approx(0.2)
    assert float(rows[3]["tau_x"]) > 0


def run_cli(*args):
    return subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "estimate.py"), *args],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )


def test_script_entry_point(folder, tmp_path):
    result = run_cli(str(folder), "--out", str(tmp_path / "o.csv"))
    assert result.returncode == 0, result.stderr
    assert "wrote 6 rows" in result.stdout


@pytest.mark.parametrize(
    "make_args,message",
    [
        (lambda d, t: [str(t / "absent.mp4")], "does not exist"),
        (lambda d, t: [str(t / "empty")], "holds no images"),
        (lambda d, t: [str(t / "garbage.mp4")], "cannot read video"),
        (lambda d, t: [str(d), "--reference", "4:9"], "out of range"),
        (lambda d, t: [str(d), "--reference", "x"], "expected a frame index"),
        (lambda d, t: [str(d), "--method", "nope"], "unknown estimator configuration"),
        (lambda d, t: [str(d), "--sensor", str(t / "absent.yaml")], "cannot read configuration"),
        (lambda d, t: [str(d), "--fps", "0"], "positive"),
    ],
)
def test_errors_are_one_line_with_exit_code_2(folder, tmp_path, capsys, make_args, message):
    (tmp_path / "empty").mkdir()
    (tmp_path / "garbage.mp4").write_bytes(b"not a video at all")
    code = main([*make_args(folder, tmp_path), "--out", str(tmp_path / "x.csv")])
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert message in err and err.startswith("estimate: error:") and "\n" not in err


def test_mismatched_frame_size_is_named(folder, tmp_path, capsys):
    cv2.imwrite(str(folder / "f99.png"), np.zeros((480, 320, 3), np.uint8))
    code = main([str(folder), "--out", str(tmp_path / "x.csv")])
    err = capsys.readouterr().err
    assert code == 2 and "frame 6" in err and "does not match the reference" in err


def test_missing_required_argument_is_a_usage_error():
    result = run_cli("somewhere")
    assert result.returncode == 2 and "--out" in result.stderr
