"""tactile estimate on real gel images, real-texture recordings and their checks."""

import csv
import dataclasses
import math
import shutil

import cv2
import numpy as np
import pytest

from controller.cli.estimate import main as estimate_main
from drivers.sim.render.real_texture import REAL_GELS_DIR
from drivers.sim.scenes.press_tilt import press_tilt_program
from evaluation.common.rendering import make_renderer
from evaluation.real_recordings.recording_checks import (
    Estimate,
    check_recording,
    quiet_ratio,
    score,
    segment_agreement,
)
from evaluation.real_recordings.recording_video import (
    TILT_NM,
    read_truth,
    recording_program,
    render_recording,
)
from evaluation.real_recordings.recordings_cli import main as check_main

CAPTURES = ("gelsight_markers_a", "digit_background_a")
SMALL = {"open_frames": 4, "press_frames": 6, "tilt_frames": 8, "release_frames": 4}


def small_program(capture):
    return dataclasses.replace(recording_program(capture), **SMALL)


@pytest.fixture(scope="module")
def recordings(tmp_path_factory):
    folder = tmp_path_factory.mktemp("recordings")
    for capture in CAPTURES:
        render_recording(capture, folder, small_program(capture), seed=3)
    return folder


def estimate_rows(path):
    with path.open() as handle:
        return list(csv.DictReader(handle))


def all_finite(rows):
    return all(math.isfinite(float(r[k])) for r in rows for k in ("tau_x", "tau_y", "tau_z"))


# --- tactile estimate on real images -----------------------------------------------------


@pytest.mark.parametrize(
    "names,sensor",
    [
        (("gelsight_markers_a.png", "gelsight_markers_b.png"), "gelsight_mini"),
        (("digit_background_a.png", "digit_background_b.jpg"), "digit"),
    ],
)
def test_estimate_on_real_image_files_is_finite(tmp_path, names, sensor):
    out = tmp_path / "out.csv"
    images = [str(REAL_GELS_DIR / name) for name in names]
    assert estimate_main([*images, "--sensor", sensor, "--out", str(out)]) == 0
    rows = estimate_rows(out)
    assert len(rows) == 2 and all_finite(rows)


def test_estimate_on_a_folder_of_real_captures_is_finite(tmp_path):
    folder = tmp_path / "captures"
    folder.mkdir()
    for name in ("gelsight_markers_a.png", "gelsight_markers_b.png"):
        shutil.copy(REAL_GELS_DIR / name, folder / name)
    out = tmp_path / "out.csv"
    assert estimate_main([str(folder), "--method", "default", "--out", str(out)]) == 0
    rows = estimate_rows(out)
    assert len(rows) == 2 and all_finite(rows)
    assert float(rows[1]["tau_x"]) != 0.0  # the second capture is pressed differently


def test_estimate_on_the_mixed_real_gels_folder_names_the_odd_image(tmp_path, capsys):
    code = estimate_main([str(REAL_GELS_DIR), "--out", str(tmp_path / "out.csv")])
    err = capsys.readouterr().err.strip()
    assert code == 2 and err.startswith("estimate: error:") and "\n" not in err
    assert "(gelsight_markers_a.png)" in err and "one sensor" in err
    assert not (tmp_path / "out.csv").exists()


def test_several_inputs_must_all_be_images(tmp_path, capsys):
    image = str(REAL_GELS_DIR / "gelsight_markers_a.png")
    code = estimate_main([image, str(REAL_GELS_DIR), "--out", str(tmp_path / "out.csv")])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "expected image files only" in err and "\n" not in err


# --- the rendered recording -----------------------------------------------------------------


@pytest.mark.parametrize("capture", CAPTURES)
def test_the_recording_round_trips_losslessly(recordings, capture):
    program = press_tilt_program(small_program(capture))
    video = cv2.VideoCapture(str(recordings / f"{capture}.mkv"))
    frames = []
    while True:
        ok, frame = video.read()
        if not ok:
            break
        frames.append(frame)
    video.release()
    assert len(frames) == len(program)
    assert {f.shape for f in frames} == {(240, 320, 3)}
    sensor = "digit" if capture.startswith("digit") else "gelsight_mini"
    renderer = make_renderer(sensor, seed=3, appearance=f"real:{capture}")
    first = renderer.render(np.zeros((30, 40, 2)), frame_index=0)  # no contact in frame 0
    assert np.array_equal(frames[0], first)  # FFV1 is lossless


def test_the_truth_follows_the_program(recordings):
    capture = CAPTURES[0]
    truth = read_truth(recordings / f"{capture}.csv")
    program = press_tilt_program(small_program(capture))
    assert truth.segments == tuple(step.segment for step in program)
    assert not truth.contact[: SMALL["open_frames"]].any() and truth.contact.any()
    assert not truth.contact[-1]  # released
    assert np.abs(truth.tau_nm).max() == pytest.approx(TILT_NM["gelsight_mini"], rel=0.05)
    for name in ("tilt_x+", "tilt_x-", "tilt_y+", "tilt_y-"):
        rows = np.array(truth.segments) == name
        axis = 0 if name.startswith("tilt_x") else 1
        sign = 1.0 if name.endswith("+") else -1.0
        assert (sign * truth.tau_nm[rows, axis] > 0).all()
        assert np.abs(truth.tau_nm[rows, 1 - axis]).max() < 1e-6


# --- the checks -----------------------------------------------------------------------------


def test_the_default_passes_the_checks_on_a_real_texture(recordings):
    check = check_recording(CAPTURES[0], recordings, "default")
    assert check.finite == 1.0, check
    assert check.quiet_ratio <= 0.05, check
    assert check.sign_agreement >= 0.95 and check.correlation > 0.0, check
    assert check.passed


@pytest.fixture(scope="module")
def truth(recordings):
    return read_truth(recordings / f"{CAPTURES[0]}.csv")


def estimate_from(tau):
    return Estimate(tau=tau, finite=np.isfinite(tau).all(axis=1), latency_ms=np.ones(len(tau)))


def test_the_truth_itself_passes(truth):
    assert score(estimate_from(2.0 * truth.tau_nm + 1e-9), truth, "truth", "t").passed


def test_a_flipped_sign_fails(truth):
    check = score(estimate_from(-truth.tau_nm), truth, "flipped", "t")
    assert check.sign_agreement == 0.0 and check.correlation < 0 and not check.passed


def test_one_flipped_axis_fails_only_its_segments(truth):
    tau = truth.tau_nm * np.array([1.0, -1.0])
    agreement = segment_agreement(tau, truth)
    assert agreement["tilt_x+"] == agreement["tilt_x-"] == 1.0
    assert agreement["tilt_y+"] == agreement["tilt_y-"] == 0.0
    assert not score(estimate_from(tau), truth, "y flipped", "t").passed


def test_an_estimate_moving_before_contact_fails_quiet(truth):
    tau = truth.tau_nm.copy()
    tau[1] = 0.1 * np.abs(truth.tau_nm).max()  # 14% of the peak |tau| before contact
    assert quiet_ratio(tau, truth.contact) > 0.05
    assert not score(estimate_from(tau), truth, "noisy", "t").passed


def test_a_non_finite_frame_fails(truth):
    tau = truth.tau_nm.copy()
    tau[-3, 0] = np.nan
    check = score(estimate_from(tau), truth, "nan", "t")
    assert check.finite < 1.0 and not check.passed


def test_an_estimate_of_another_length_is_refused(truth):
    with pytest.raises(ValueError, match="frames"):
        score(estimate_from(truth.tau_nm[:-1]), truth, "short", "t")


# --- the tool -------------------------------------------------------------------------------


def test_the_tool_writes_its_table(tmp_path, capsys, monkeypatch):
    import evaluation.real_recordings.recordings_cli as cli

    monkeypatch.setattr(
        cli,
        "render_recording",
        lambda capture, work, seed: render_recording(capture, work, small_program(capture), seed),
    )
    table = tmp_path / "table.md"
    args = ["--estimators", "default", "--captures", CAPTURES[0], "--work", str(tmp_path / "w")]
    assert check_main([*args, "--table", str(table)]) == 0
    text = table.read_text()
    assert f"| `default` | {CAPTURES[0]} |" in text and "| yes |" in text
    assert (tmp_path / "w" / f"{CAPTURES[0]}.default.csv").is_file()


@pytest.mark.parametrize(
    "args,message",
    [
        (["--captures", "nope"], "unknown nope"),
        (["--estimators", "nope"], "nope"),
        (["--estimators", ","], "expected a comma-separated list"),
    ],
)
def test_tool_errors_are_one_line_with_exit_code_2(tmp_path, capsys, args, message):
    code = check_main([*args, "--work", str(tmp_path / "w")])
    err = capsys.readouterr().err.strip()
    assert code == 2 and err.startswith("check_real_recordings: error:") and message in err
    assert "\n" not in err and not (tmp_path / "w").exists()
