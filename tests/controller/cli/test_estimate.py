"""The offline estimator as a user runs it: tactile estimate ..."""

import csv
import json
import os
import resource
import signal
import subprocess
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

from controller.cli.estimate import CSV_COLUMNS, main
from controller.tactile.calibration import AxisFit, Calibration, estimator_sha256
from controller.tactile.estimator import TactileEstimator
from controller.tactile.settings import sensor_estimator
from core.sensor_profile import sensor_profile
from drivers.sim.render.marker_images import MarkerImageRenderer
from drivers.sim.scenes.synthetic_sequence import phase_patterns
from tests.script_runs import exit_code
from tests.video_faults import corrupt_frame, truncate_inside_frame, write_mjpg

ROOT = Path(__file__).resolve().parents[3]


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


def test_missing_required_argument_is_a_usage_error(capsys):
    assert exit_code("estimate", ["somewhere"]) == 2 and "--out" in capsys.readouterr().err


# --- outputs never clobber inputs or earlier results -----------------------------------------


def write_video(path, frames, fps=25.0):
    return write_mjpg(path, frames, fps)


def run_main(capsys, *args):
    code = main([str(a) for a in args])
    captured = capsys.readouterr()
    return code, captured.err.strip()


def assert_one_error_line(err, message):
    assert err.startswith("estimate: error:") and "\n" not in err, err
    assert message in err, err


def test_out_equal_to_the_input_video_is_refused_and_the_video_kept(frames, tmp_path, capsys):
    video = write_video(tmp_path / "v.avi", frames)
    before = video.read_bytes()
    (tmp_path / "link.avi").hardlink_to(video)
    for out in (video, tmp_path / "link.avi", tmp_path / "." / "v.avi"):
        code, err = run_main(capsys, video, "--out", out)
        assert code == 2
        assert_one_error_line(err, "is the input")
    assert video.read_bytes() == before


def test_out_inside_the_input_folder_is_refused(folder, capsys):
    before = (folder / "f5.png").read_bytes()
    for name in ("f5.png", "estimates.csv"):
        code, err = run_main(capsys, folder, "--out", folder / name)
        assert code == 2
        assert_one_error_line(err, "inside the input folder")
    assert (folder / "f5.png").read_bytes() == before
    assert sorted(p.name for p in folder.iterdir()) == sorted(f"f{i * 5}.png" for i in range(6))


def test_out_equal_to_a_configuration_input_is_refused(folder, tmp_path, capsys):
    sensor = tmp_path / "mini.yaml"
    sensor.write_text((ROOT / "configs" / "sensors" / "gelsight_mini.yaml").read_text())
    code, err = run_main(capsys, folder, "--sensor", sensor, "--out", sensor)
    assert code == 2 and "is the input" in err
    assert "width_px" in sensor.read_text()


@pytest.mark.parametrize(
    "out,message",
    [("/dev/full", "not a regular file"), (".", "is a folder"), ("f.png/x.csv", "is a file")],
)
def test_unwritable_outputs_are_refused_before_any_frame_is_read(
    folder, tmp_path, capsys, monkeypatch, out, message
):
    (tmp_path / "f.png").write_bytes(b"")
    monkeypatch.chdir(tmp_path)
    import controller.cli.estimate as cli

    monkeypatch.setattr(cli, "open_source", lambda path: pytest.fail("work began"))
    code, err = run_main(capsys, folder, "--out", out)
    assert code == 2
    assert_one_error_line(err, message)


def test_mixed_frame_sizes_keep_the_previous_csv(folder, tmp_path, capsys):
    out = tmp_path / "x.csv"
    assert main([str(folder), "--out", str(out)]) == 0
    good = out.read_text()
    cv2.imwrite(str(folder / "f99.png"), np.zeros((480, 320, 3), np.uint8))
    code, err = run_main(capsys, folder, "--out", out)
    assert code == 2 and "frame 6" in err and "nothing written" in err
    assert out.read_text() == good
    assert [p.name for p in tmp_path.iterdir() if "partial" in p.name] == []


# --- interruption -------------------------------------------------------------------------------


def push_that_signals(signum, at_frame):
    original = TactileEstimator.push
    calls = []

    def push(self, frame, t_s):
        calls.append(t_s)
        if len(calls) == at_frame:
            os.kill(os.getpid(), signum)
        return original(self, frame, t_s)

    return push


@pytest.mark.parametrize(
    "signum,code,word", [(signal.SIGINT, 130, "SIGINT"), (signal.SIGTERM, 143, "SIGTERM")]
)
def test_a_signal_mid_run_exits_cleanly_and_keeps_the_previous_csv(
    folder, tmp_path, capsys, monkeypatch, signum, code, word
):
    out = tmp_path / "x.csv"
    out.write_text("previous\n")
    monkeypatch.setattr(TactileEstimator, "push", push_that_signals(signum, 3))
    before = signal.getsignal(signal.SIGTERM)
    assert main([str(folder), "--out", str(out)]) == code
    err = capsys.readouterr().err.strip()
    assert err.startswith("estimate: ") and word in err and "\n" not in err
    assert "Traceback" not in err
    assert out.read_text() == "previous\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["frames", "x.csv"]
    assert signal.getsignal(signal.SIGTERM) is before  # the handler is restored


SLOW_RUN = """
import sys, time
from controller.tactile.estimator import TactileEstimator
from controller.cli.estimate import main
original = TactileEstimator.push
def slow(self, frame, t_s):
    time.sleep(0.3)
    return original(self, frame, t_s)
TactileEstimator.push = slow
sys.exit(main(sys.argv[1:]))
"""


@pytest.mark.parametrize("signum,code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_a_signal_from_outside_ends_the_process_in_one_line(folder, tmp_path, signum, code):
    out = tmp_path / "x.csv"
    out.write_text("previous\n")
    process = subprocess.Popen(
        [sys.executable, "-c", SLOW_RUN, str(folder), "--out", str(out)],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 30
    while not any("partial" in p.name for p in tmp_path.iterdir()):  # the CSV is being written
        assert time.monotonic() < deadline and process.poll() is None
        time.sleep(0.02)
    process.send_signal(signum)
    _, err = process.communicate(timeout=30)
    assert process.returncode == code
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    assert out.read_text() == "previous\n"
    assert not any("partial" in p.name for p in tmp_path.iterdir())


def test_a_full_disk_is_one_line_and_keeps_the_previous_csv(folder, tmp_path):
    out = tmp_path / "x.csv"
    out.write_text("previous\n")
    limit = 600  # bytes: the header and a few rows fit, the whole CSV does not

    def small_files():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # writes fail with EFBIG instead
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    result = subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "estimate.py"), str(folder), "--out", str(out)],
        capture_output=True,
        text=True,
        cwd=ROOT,
        preexec_fn=small_files,
    )
    assert result.returncode == 2, result.stderr
    err = result.stderr.strip()
    assert err.startswith("estimate: error:") and "File too large" in err and "\n" not in err
    assert out.read_text() == "previous\n"
    assert not any("partial" in p.name for p in tmp_path.iterdir())


# --- damaged video --------------------------------------------------------------------------


@pytest.fixture
def clip(tmp_path):
    renderer = MarkerImageRenderer(rng=np.random.default_rng(8))
    tilt = phase_patterns((240, 320))["tilt_x"]
    images = [renderer.render(a * tilt) for a in np.linspace(0.0, 1.0, 12)]
    return write_video(tmp_path / "clip.avi", images, fps=20.0)


def rows_of(path):
    return [(int(r["frame"]), float(r["time_s"])) for r in read_rows(path)]


def test_truncated_video_is_an_error_naming_what_was_read(clip, tmp_path, capsys):
    truncate_inside_frame(clip, 7)
    out = tmp_path / "x.csv"
    code, err = run_main(capsys, clip, "--out", out)
    assert code == 2
    assert_one_error_line(err, "header says 12 frames, but it ends after frame 7 (8 frames read)")
    assert "--allow-damaged" in err and not out.exists()
    code, err = run_main(capsys, clip, "--out", out, "--reference", "9:11")
    assert_one_error_line(err, "ended after 8 frames (its header says 12)")


def test_truncated_video_with_allow_damaged_warns_and_keeps_true_times(clip, tmp_path, capsys):
    truncate_inside_frame(clip, 7)
    out = tmp_path / "x.csv"
    code, err = run_main(capsys, clip, "--out", out, "--allow-damaged")
    assert code == 0
    lines = err.splitlines()  # the loss, and the choice made without --open (one line each)
    assert all(line.startswith("estimate: warning:") for line in lines)
    assert len([line for line in lines if "header says 12 frames" in line]) == 1
    assert len(lines) == 2 and "no open gel given" in lines[0]
    assert rows_of(out) == [(i, pytest.approx(i / 20.0)) for i in range(8)]


def test_corrupted_frame_is_reported_and_later_frames_keep_their_times(clip, tmp_path, capsys):
    corrupt_frame(clip, 5)
    out = tmp_path / "x.csv"
    code, err = run_main(capsys, clip, "--out", out)
    assert code == 2
    assert_one_error_line(err, "1 frames are missing or did not decode (frames 5)")
    code, err = run_main(capsys, clip, "--out", out, "--allow-damaged", "--fps", "10")
    assert code == 0 and "frames 5" in err
    expected = [(i, pytest.approx(i / 10.0)) for i in range(12) if i != 5]
    assert rows_of(out) == expected  # frame 6 is still at 0.6 s
    code, err = run_main(capsys, clip, "--out", out, "--reference", "4:7")
    assert_one_error_line(err, "1 of these frames")


def test_unreadable_image_in_a_folder_is_reported(folder, tmp_path, capsys):
    (folder / "f7.png").write_bytes(b"not an image")
    code, err = run_main(capsys, folder, "--out", tmp_path / "x.csv")
    assert code == 2
    assert_one_error_line(err, "1 images did not decode (f7.png)")
    code, err = run_main(capsys, folder, "--out", tmp_path / "x.csv", "--allow-damaged")
    assert code == 0 and "f7.png" in err
    frames_written = [n for n, _ in rows_of(tmp_path / "x.csv")]
    assert frames_written == [0, 1, 3, 4, 5, 6]  # f7 sorts third (f0, f5, f7, f10, ...)


# --- nonsense refused -----------------------------------------------------------------------


@pytest.mark.parametrize("fps", ["1e-300", "nan", "inf", "-25", "1e9"])
def test_absurd_frame_rates_are_refused(folder, tmp_path, capsys, fps):
    code, err = run_main(capsys, folder, "--out", tmp_path / "x.csv", "--fps", fps)
    assert code == 2
    assert_one_error_line(err, "expected a positive number of frames per second")


@pytest.mark.parametrize("sensor", ["nope", "digit_gel", "gelsight_mini_camera"])
def test_sensor_errors_list_only_sensor_profiles(folder, tmp_path, capsys, sensor):
    code, err = run_main(capsys, folder, "--out", tmp_path / "x.csv", "--sensor", sensor)
    assert code == 2
    assert_one_error_line(err, "expected one of: digit, gelsight_mini (or a path")
    assert "_gel," not in err and "_camera," not in err
    assert err.count("expected") == 1  # the hint is given once


# --- calibration fitted for something else ----------------------------------------------------


def write_calibration(path, sensor="gelsight_mini", method="default", digest=True, fmt=None):
    config = sensor_estimator(sensor_profile("gelsight_mini"), method)[1]
    fit = {"tau_x": AxisFit(0.004, 0.0, 0.001, 0.99, 100)}
    text = Calibration(sensor, method, fit, estimator_sha256(config) if digest else None)
    text = text.to_yaml()
    if fmt == "v1":
        text = text.replace("calibration/v2", "calibration/v1").replace(
            "estimator_sha256: null\n", ""
        )
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    "kwargs,args,message",
    [
        ({"sensor": "digit"}, [], "fitted for sensor 'digit', not 'gelsight_mini'"),
        ({}, ["--method", "paper"], "fitted for the estimator configuration 'default'"),
        ({"method": "paper"}, [], "fitted for the estimator configuration 'paper'"),
        ({"digest": False, "fmt": "v1"}, [], "does not record which estimator"),
    ],
)
def test_a_calibration_for_something_else_needs_force(
    folder, tmp_path, capsys, kwargs, args, message
):
    calibration = write_calibration(tmp_path / "cal.yaml", **kwargs)
    out = tmp_path / "x.csv"
    code, err = run_main(capsys, folder, "--out", out, "--calibration", calibration, *args)
    assert code == 2 and not out.exists()
    assert_one_error_line(err, message)
    assert "--force" in err
    code, err = run_main(
        capsys, folder, "--out", out, "--calibration", calibration, "--force", *args
    )
    assert code == 0 and err.startswith("estimate: warning:") and message in err


def test_a_matching_calibration_applies(folder, tmp_path, capsys):
    calibration = write_calibration(tmp_path / "cal.yaml")
    out = tmp_path / "x.csv"
    code, err = run_main(capsys, folder, "--out", out, "--calibration", calibration)
    assert code == 0 and err == ""
    raw = tmp_path / "raw.csv"
    assert main([str(folder), "--out", str(raw)]) == 0
    calibrated = [float(r["tau_x"]) for r in read_rows(out)]
    assert calibrated == pytest.approx([0.004 * float(r["tau_x"]) for r in read_rows(raw)])


@pytest.mark.parametrize(
    "text,message",
    [
        ("axes: [1, 2]", "key 'axes': expected a mapping"),
        ("axes: 5", "key 'axes': expected a mapping"),
        ("sensor: [a]", "key 'sensor'"),
    ],
)
def test_broken_calibration_files_are_one_line_errors(folder, tmp_path, capsys, text, message):
    calibration = write_calibration(tmp_path / "cal.yaml")
    key = text.split(":")[0]
    lines = [
        line for line in calibration.read_text().splitlines() if not line.startswith(key + ":")
    ]
    if key == "axes":
        lines = [line for line in lines if not line.startswith("  ")]
    calibration.write_text("\n".join(lines) + "\n" + text + "\n")
    code, err = run_main(capsys, folder, "--out", tmp_path / "x.csv", "--calibration", calibration)
    assert code == 2
    assert_one_error_line(err, message)


def test_a_binary_calibration_file_is_a_one_line_error(folder, tmp_path, capsys):
    calibration = tmp_path / "cal.yaml"
    calibration.write_bytes(bytes(range(256)))
    code, err = run_main(capsys, folder, "--out", tmp_path / "x.csv", "--calibration", calibration)
    assert code == 2 and err.startswith("estimate: error:") and "\n" not in err


def test_open_frames_locate_the_contact_for_grid_lk(tmp_path, capsys, monkeypatch):
    """--open A:B hands those frames to the estimator as the open gel before the reference
    (grid_lk then takes its tilt about the grasp); a bad range is a one-line error."""
    renderer = MarkerImageRenderer(rng=np.random.default_rng(5))
    ys, xs = np.mgrid[0:240, 0:320].astype(float)
    k = 2.0 / 30.0 * np.exp(-((xs - 200) ** 2 + (ys - 100) ** 2) / (2 * 30.0**2))
    grasp = np.stack([k * (xs - 200), k * (ys - 100)], axis=-1)
    path = tmp_path / "grasp"
    path.mkdir()
    for i, frame in enumerate([renderer.render()] * 2 + [renderer.render(grasp)] * 3):
        cv2.imwrite(str(path / f"f{i}.png"), frame)
    centres = []
    original = TactileEstimator.set_reference

    def spy(self, frames):
        original(self, frames)
        centres.append(self.contact_centre_mm)

    monkeypatch.setattr(TactileEstimator, "set_reference", spy)
    out = tmp_path / "out.csv"
    args = [str(path), "--method", "default", "--reference", "2:4", "--out", str(out)]
    assert main([*args, "--open", "0:2"]) == 0
    assert main(args) == 0
    assert centres[0] is not None and centres[0][0] > 1.5 and centres[1] is None
    assert len(read_rows(out)) == 5
    assert capsys.readouterr().err == ""  # the open gel as it should be: no warning
    assert main([*args, "--open", "3:9"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("estimate: error: --open 3:9 and --reference 2:4 overlap") and (
        "\n" not in err
    )


@pytest.fixture
def grasp_folder(tmp_path):
    """Two frames of the open gel, then four of a grasp (a spreading press at (200, 100))."""
    renderer = MarkerImageRenderer(rng=np.random.default_rng(5))
    ys, xs = np.mgrid[0:240, 0:320].astype(float)
    k = 2.0 / 30.0 * np.exp(-((xs - 200) ** 2 + (ys - 100) ** 2) / (2 * 30.0**2))
    grasp = renderer.render(np.stack([k * (xs - 200), k * (ys - 100)], axis=-1))
    path = tmp_path / "grasp"
    path.mkdir()
    for i, frame in enumerate([renderer.render()] * 2 + [grasp] * 4):
        cv2.imwrite(str(path / f"f{i}.png"), frame)
    return path


@pytest.mark.parametrize(
    "open_gel, code, message",
    [
        ("0:5", 2, "error: --open 0:5 and --reference 4:6 overlap: the open gel"),
        ("4", 2, "error: --open 4:5 and --reference 4:6 overlap: the open gel"),
        ("6:8", 2, "error: --open 6:8 comes after --reference 4:6: the open gel"),
        ("2:4", 0, "warning: --open 2:4: frame 0 differs from frame 2 by"),  # during the press
        ("1:3", 0, "warning: --open 1:3: frame 2 differs from frame 1 by"),  # the press begins
    ],
)
def test_open_frames_that_are_not_the_open_gel(
    grasp_folder, tmp_path, capsys, open_gel, code, message
):
    """Before or overlapping the reference: refused. Not the open gel by their content (a
    press during them): estimated, with one warning naming the frame."""
    out = tmp_path / "out.csv"
    args = [str(grasp_folder), "--reference", "4:6", "--open", open_gel, "--out", str(out)]
    assert main(args) == code
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"estimate: {message}") and "\n" not in err
    assert len(read_rows(out)) == 6 if code == 0 else not out.exists()


def _damaged_inputs(folder, tmp_path):
    """Inputs whose decoders write to stderr themselves: a PNG with a bad CRC (libpng), a
    truncated JPEG (libjpeg), a truncated BMP (OpenCV's log), an AVI cut inside its header
    (OpenCV's AVI parser)."""
    good = (folder / "f0.png").read_bytes()
    bad_crc = bytearray(good)
    bad_crc[100:110] = b"x" * 10
    (folder / "f1.png").write_bytes(bytes(bad_crc))
    image = cv2.imread(str(folder / "f0.png"))
    for suffix in ("jpg", "bmp"):
        cv2.imwrite(str(tmp_path / f"a.{suffix}"), image)
        data = (tmp_path / f"a.{suffix}").read_bytes()
        (folder / f"f2.{suffix}").write_bytes(data[: len(data) // 2])
    video = write_mjpg(tmp_path / "v.avi", [image] * 3, fps=20.0)
    (tmp_path / "cut.avi").write_bytes(video.read_bytes()[:200])
    return [[str(folder)], [str(tmp_path / "cut.avi")]]


def test_the_decoders_own_messages_never_reach_the_terminal(folder, tmp_path, capfd):
    """Read at the file descriptors: a decoder writes to descriptor 2 itself, past Python."""
    for inputs in _damaged_inputs(folder, tmp_path):
        code = exit_code("estimate", [*inputs, "--out", str(tmp_path / "x.csv")])
        err = capfd.readouterr().err.strip()
        assert code == 2 and err.startswith("estimate: error:"), err
        assert "\n" not in err, err


def _tilt_x_columns(path: Path) -> tuple[np.ndarray, np.ndarray]:
    with path.open() as handle:
        rows = list(csv.DictReader(handle))
    return (
        np.array([float(r["tau_x"]) for r in rows]),
        np.array([int(r["degenerate"]) for r in rows]),
    )


def _recording_folders(tmp_path: Path, push: float) -> tuple[object, dict[str, Path]]:
    """A varied contact tilted about x (seed 314, 20 frames) as recorded in the grasp
    ("grasped": its 4 reference frames, then the tilt) and from the open gel on ("opened")."""
    from evaluation.realgel.sequences import SequenceSpec, render

    spec = SequenceSpec("gelsight_background", "x", push, 0.4, 3.0, 314, 20, contact="varied")
    sequence = render(spec, 4)
    frames = [*sequence.references, *sequence.frames]  # an old recording, in the grasp
    folders = {}
    for name, recorded in (("grasped", frames), ("opened", [*sequence.open_frames, *frames])):
        folders[name] = tmp_path / f"{name}{push}"
        folders[name].mkdir()
        for index, frame in enumerate(recorded):
            cv2.imwrite(str(folders[name] / f"f{index:03d}.png"), frame)
    return sequence, folders


@pytest.mark.parametrize("push", [0.0, 0.4])
def test_without_open_frames_the_tool_takes_the_contact_from_the_whole_recording(
    tmp_path, capsys, push
):
    """Zeroed on a grasp (no --open), the tool finds the contact's support in the
    whole recording and estimates it again about it, says so in one line and records the
    choice beside the CSV. A weak tilt alone never establishes a contact, and the no-contact
    gate would zero most of it: that recording is estimated without the gate, and since its
    change is not clearly above the camera noise, on the whole grid (no support) through the
    paper's EMA. With
    --open the tool keeps the configuration and removes an old record."""
    from dataclasses import replace

    from controller.cli.estimate import fallback_sidecar
    from controller.offline.recording_support import (
        NOISE_EMA_ALPHA,
        SUPPORT_REASON,
        UNGATED_REASON,
        WHOLE_GRID_REASON,
        recording_support,
    )

    weak = push == 0.0
    sequence, folders = _recording_folders(tmp_path, push)
    frames = [*sequence.references, *sequence.frames]
    out = tmp_path / "x.csv"
    sidecar = fallback_sidecar(out)
    assert main([str(folders["grasped"]), "--reference", "0:4", "--out", str(out)]) == 0
    err = capsys.readouterr().err.strip()
    reason = WHOLE_GRID_REASON if weak else SUPPORT_REASON
    assert err.count("\n") == 0 and reason in err and sidecar.name in err
    assert (UNGATED_REASON in err) == weak
    record = json.loads(sidecar.read_text())
    assert record["estimator"] == "default" and reason in record["reason"]
    assert ("noise_gate" in record) == weak
    # the same, step by step: a first pass for the divergences, then about their support
    profile = sensor_profile("gelsight_mini")
    config = sensor_estimator(profile)[1]
    first = TactileEstimator(config, profile)
    first.set_reference(sequence.references)
    divergences = []
    for frame in frames:
        first.push(frame, 0.0)
        divergences.append(first.field_divergence())
    field = first.field
    support = recording_support(divergences, field.x_mm, field.y_mm)
    if weak:  # at the noise: ungated, through the paper's EMA
        config = replace(config, noise_gate=None, ema_alpha=NOISE_EMA_ALPHA)
    second = TactileEstimator(config, profile)
    if weak:
        assert support is None and record["contact_support"] is None
        assert record["ema_alpha"] == NOISE_EMA_ALPHA
    else:
        assert support is not None
        centre = record["contact_support"]["centre_mm"]
        assert centre == pytest.approx(support.centre_mm, abs=1e-4)
        second.set_contact_support(support)
    second.set_reference(sequence.references)
    expected = [second.push(frame, 0.0).tau_x for frame in frames]
    tau_x, degenerate = _tilt_x_columns(out)
    np.testing.assert_allclose(tau_x, expected, rtol=1e-8, atol=1e-12)
    assert not degenerate[4:].any()
    # with the open gel the tool keeps the configuration, and the old record goes
    args = [str(folders["opened"]), "--reference", "4:8", "--open", "0:4", "--out", str(out)]
    assert main(args) == 0
    assert capsys.readouterr().err == "" and not sidecar.exists()
