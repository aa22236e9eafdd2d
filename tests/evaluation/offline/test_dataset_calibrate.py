"""Dataset format round trip, its errors, and tactile calibrate on a small simulated jig
dataset."""

import os
import re
import shutil
import signal
from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml

from controller.cli.calibrate import main as calibrate_main
from controller.offline.dataset import META, Dataset, DatasetMeta, DatasetWriter
from controller.tactile.calibration import Calibration
from controller.tactile.settings import sensor_estimator
from core.config import ConfigError
from core.sensor_profile import sensor_profile
from drivers.sim.render.marker_images import MarkerImageRenderer
from drivers.sim.scenes.jig import Experiment
from evaluation.common.sim_setup import gel_model, jig_config
from evaluation.offline.jig_dataset import write_jig_dataset
from evaluation.offline.make_dataset_cli import main as make_dataset_main
from tests.conftest import made_once
from tests.video_faults import corrupt_frame, truncate_inside_frame


class _ExactRenderer:
    """The exact spline renderer behind the FrameRenderer interface (full-size field)."""

    def __init__(self) -> None:
        self._renderer = MarkerImageRenderer(rng=np.random.default_rng(2))

    def render(self, displacement_px: np.ndarray, *, frame_index: int) -> np.ndarray:
        full = cv2.resize(displacement_px.astype(np.float32), (320, 240))
        return self._renderer.render(full)


def _write_plate_dataset(folder: Path) -> None:
    write_jig_dataset(
        folder,
        "gelsight_mini",
        gel_model("gelsight_mini", "plate"),
        _ExactRenderer(),
        [Experiment("x", 0.04, 4)],
        jig_config(),
        seed=5,
    )


@pytest.fixture(scope="module")
def dataset_folder(run_root) -> Path:
    """A simulated jig dataset, written once per test run (tests/conftest.py); read only."""
    return made_once(run_root, "jig_plate_dataset", _write_plate_dataset)


def test_dataset_round_trip(dataset_folder):
    dataset = Dataset(dataset_folder)
    assert dataset.meta.sensor == "gelsight_mini"
    assert dataset.meta.gel_load_factor == -0.5
    assert [s.axis for s in dataset.meta.segments] == ["x"]
    frames = list(dataset.frames())
    assert len(frames) == len(dataset) > 50
    assert [t for _, t, _ in frames] == pytest.approx(list(dataset.frame_t_s))
    assert frames[0][2].shape == (240, 320, 3)
    assert dataset.in_interval(dataset.meta.reference).sum() >= 20
    t, gel = dataset.gel_truth()
    assert gel[:, 3] == pytest.approx(-0.5 * dataset.ft_wrench[:, 3])
    assert dataset.truth is not None and "slip_fraction" in dataset.truth


def test_calibrate_fits_the_dipole_and_writes_a_calibration(dataset_folder, tmp_path, capsys):
    out = tmp_path / "cal.yaml"
    assert calibrate_main([str(dataset_folder), "--out", str(out)]) == 0
    table = capsys.readouterr().out
    assert "| tau_x |" in table
    calibration = Calibration.load(out)
    assert set(calibration.axes) == {"tau_x", "fv_tau_x"}
    assert calibration.axes["tau_x"].slope > 0
    assert calibration.axes["tau_x"].r2 > 0.95


def test_bad_dataset_errors_name_the_file_and_key(dataset_folder, tmp_path, capsys):
    assert calibrate_main([str(tmp_path)]) == 2
    assert "not a dataset folder" in capsys.readouterr().err
    broken = tmp_path / "broken"
    broken.mkdir()
    for name in ("tactile.csv", "ft.csv", "tactile.avi"):
        (broken / name).write_bytes((dataset_folder / name).read_bytes())
    meta = yaml.safe_load((dataset_folder / META).read_text())
    meta["segments"][0]["axis"] = "w"
    (broken / META).write_text(yaml.safe_dump(meta))
    with pytest.raises(ConfigError, match=r"segments\[0\]\.axis"):
        Dataset(broken)
    del meta["gel_load_factor"]
    (broken / META).write_text(yaml.safe_dump(meta))
    with pytest.raises(ConfigError, match="gel_load_factor"):
        Dataset(broken)
    meta = yaml.safe_load((dataset_folder / META).read_text())
    (broken / META).write_text(yaml.safe_dump(meta))
    (broken / "ft.csv").write_text("t,fx\n0,1\n")
    with pytest.raises(ConfigError, match="ft.csv: expected the header"):
        Dataset(broken)


# --- incomplete, inconsistent and broken datasets are refused --------------------------------


@pytest.fixture
def copy(dataset_folder, tmp_path) -> Path:
    target = tmp_path / "copy"
    shutil.copytree(dataset_folder, target)
    return target


def edit_meta(folder: Path, change) -> None:
    meta = yaml.safe_load((folder / META).read_text())
    change(meta)
    (folder / META).write_text(yaml.safe_dump(meta))


def calibrate_error(folder, capsys, *args) -> str:
    assert calibrate_main([str(folder), *map(str, args)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("calibrate: error:") and "\n" not in err, err
    return err


def late_segments(meta):  # the interrupted make_dataset: segments listed beyond the frames
    last = meta["segments"][-1]
    meta["segments"].append(
        {"axis": "y", "amplitude_nm": 0.04, "t_start_s": last["t_end_s"], "t_end_s": 1324.0}
    )


@pytest.mark.parametrize(
    "change,message",
    [
        (late_segments, "lies outside the frames"),
        (lambda m: m.update(segments=5), "key 'segments': expected a list"),
        (lambda m: m.update(segments=[5]), "segments[0]"),
        (lambda m: m.update(gel_load_factor=True), "gel_load_factor"),
        (lambda m: m.update(gel_load_factor=0), "non-zero"),
        (lambda m: m.update(reference=[500.0, 501.0]), "key 'reference': no frame"),
        (lambda m: m.update(reference=[2.0, float("nan")]), "key 'reference'"),
        (lambda m: m["segments"][0].update(t_end_s=m["segments"][0]["t_start_s"]), "t_end_s"),
        (lambda m: m["segments"][0].update(amplitude_nm=float("inf")), "amplitude_nm"),
        (lambda m: m.update(format="tactile-insertion/dataset/v0"), "key 'format'"),
        (lambda m: m.update(surprise=1), "unknown key 'surprise'"),
        (lambda m: m.update(extras=[1]), "key 'extras'"),
    ],
)
def test_meta_that_disagrees_with_the_data_is_refused(copy, capsys, change, message):
    edit_meta(copy, change)
    with pytest.raises(ConfigError, match=re.escape(message)):
        Dataset(copy)
    assert message in calibrate_error(copy, capsys)


def rewrite_csv(path: Path, change) -> None:
    lines = path.read_text().splitlines()
    path.write_text("\n".join(change(lines)) + "\n")


def swap_rows(lines):
    lines[5], lines[6] = lines[6], lines[5]
    return lines


@pytest.mark.parametrize(
    "name,change,message",
    [
        ("tactile.csv", swap_rows, "column 't_s' must increase"),
        (
            "tactile.csv",
            lambda ls: [ls[0]] + [f"{i + 1},{row.split(',')[1]}" for i, row in enumerate(ls[1:])],
            "column 'frame' must count",
        ),
        (
            "tactile.csv",
            lambda ls: (
                [ls[0]]
                + [
                    f"{i},{row.split(',')[1]}"
                    for i, row in enumerate(sorted(ls[1:], key=lambda r: -float(r.split(",")[1])))
                ]
            ),
            "column 't_s' must increase",
        ),
        ("tactile.csv", lambda ls: ls[:-40], "header says"),
        ("ft.csv", swap_rows, "column 't_s' must increase"),
        ("ft.csv", lambda ls: ls[:1], "at least one row"),
        ("ft.csv", lambda ls: ls + ["1,2,3"], "expected numbers in every row"),
        ("truth.csv", lambda ls: [], "expected a header"),
        ("truth.csv", lambda ls: ls[:1], "one row per frame"),
        ("truth.csv", lambda ls: ls + ["x" * 3], "expected numbers"),
    ],
)
def test_broken_tables_are_refused(copy, capsys, name, change, message):
    rewrite_csv(copy / name, change)
    with pytest.raises(ConfigError, match=re.escape(message)):
        Dataset(copy)
    calibrate_error(copy, capsys)


def test_an_empty_truth_csv_is_an_error(copy, capsys):
    (copy / "truth.csv").write_text("")
    assert "truth.csv" in calibrate_error(copy, capsys)


def test_a_truncated_dataset_video_is_refused(copy, capsys):
    truncate_inside_frame(copy / "tactile.avi", 30)
    with pytest.raises(ConfigError, match="tactile.avi"):
        dataset = Dataset(copy)
        list(dataset.frames())
    assert "tactile.avi" in calibrate_error(copy, capsys)


def test_a_corrupted_dataset_frame_is_refused(copy, capsys):
    corrupt_frame(copy / "tactile.avi", 30)
    dataset = Dataset(copy)
    with pytest.raises(ConfigError, match="frames 30-30 are missing or did not decode"):
        list(dataset.frames())
    assert "frames 30-30" in calibrate_error(copy, capsys)


def test_an_axis_whose_segments_cannot_be_fitted_is_an_error(copy, capsys):
    frame_t = np.loadtxt(copy / "tactile.csv", delimiter=",", skiprows=1)[:, 1]
    segment = {"axis": "y", "amplitude_nm": 0.04}  # holds a single frame: too few to fit
    segment.update(t_start_s=float(frame_t[40]), t_end_s=float(frame_t[41]))
    edit_meta(copy, lambda m: m["segments"].append(segment))
    err = calibrate_error(copy, capsys)
    assert "cannot fit tau_y" in err and "only 1 estimate samples" in err


# --- calibrate's output ----------------------------------------------------------------------


@pytest.mark.parametrize(
    "out,message",
    [
        ("{d}/meta.yaml", "inside the input folder"),
        ("{t}", "is a folder"),
        ("/dev/full", "not a regular file"),
        ("{d}/../copy/x/y.yaml", "inside the input folder"),
    ],
)
def test_calibrate_checks_out_before_any_work(copy, tmp_path, capsys, monkeypatch, out, message):
    import controller.cli.calibrate as cli

    monkeypatch.setattr(cli, "estimate_dataset", lambda *a: pytest.fail("work began"))
    before = (copy / META).read_bytes()
    err = calibrate_error(copy, capsys, "--out", out.format(d=copy, t=tmp_path))
    assert message in err
    assert (copy / META).read_bytes() == before


def test_the_calibration_records_what_it_was_fitted_for(dataset_folder, tmp_path, capsys):
    out = tmp_path / "cal.yaml"
    method = "dis_ultrafast"
    assert calibrate_main([str(dataset_folder), "--out", str(out), "--method", method]) == 0
    calibration = Calibration.load(out)
    paper = sensor_estimator(sensor_profile("gelsight_mini"), method)[1]
    default = sensor_estimator(sensor_profile("gelsight_mini"), "default")[1]
    assert calibration.sensor == "gelsight_mini" and calibration.estimator == method
    assert calibration.mismatch("gelsight_mini", paper) is None
    assert f"estimator configuration '{method}'" in calibration.mismatch("gelsight_mini", default)
    assert "sensor 'gelsight_mini', not 'digit'" in calibration.mismatch("digit", paper)


# --- writing datasets: all or nothing ---------------------------------------------------------


def small_meta(sensor="gelsight_mini") -> DatasetMeta:
    return DatasetMeta(sensor, "recording", -0.5, (0.0, 0.2), None, (), {})


def test_an_abandoned_writer_leaves_no_dataset(tmp_path):
    """A process killed mid-write: no destination, and the hidden partial folder has no
    meta.yaml, so nothing reads it as a dataset."""
    target = tmp_path / "d"
    writer = DatasetWriter(target, small_meta(), 10.0)
    writer.add_frame(0.0, np.zeros((240, 320, 3), np.uint8))
    writer._frames.flush()  # what a killed process leaves on disk
    assert not target.exists()
    (partial,) = [p for p in tmp_path.iterdir()]
    assert partial.name.startswith(".d.") and "partial" in partial.name
    with pytest.raises(ConfigError, match="not a dataset folder"):
        Dataset(partial)
    writer.abort()
    assert list(tmp_path.iterdir()) == []


def test_a_failed_write_keeps_the_previous_dataset(dataset_folder, tmp_path):
    target = tmp_path / "d"
    shutil.copytree(dataset_folder, target)
    before = (target / META).read_text()
    with pytest.raises(RuntimeError), DatasetWriter(target, small_meta(), 10.0, replace=True) as w:
        w.add_frame(0.0, np.zeros((240, 320, 3), np.uint8))
        raise RuntimeError("renderer failed")
    assert (target / META).read_text() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d"]
    with pytest.raises(FileExistsError):
        DatasetWriter(target, small_meta(), 10.0)


class _SignallingRenderer(_ExactRenderer):
    def __init__(self, signum: int, at_frame: int) -> None:
        super().__init__()
        self.signum, self.at_frame = signum, at_frame

    def render(self, displacement_px: np.ndarray, *, frame_index: int) -> np.ndarray:
        if frame_index == self.at_frame:
            os.kill(os.getpid(), self.signum)
        return super().render(displacement_px, frame_index=frame_index)


@pytest.mark.parametrize("signum,code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_interrupted_make_dataset_writes_nothing(tmp_path, capsys, monkeypatch, signum, code):
    import evaluation.offline.make_dataset_cli as cli

    monkeypatch.setattr(cli, "make_renderer", lambda *a, **k: _SignallingRenderer(signum, 20))
    out = tmp_path / "d"
    assert make_dataset_main([str(out), "--frames-per-axis", "30"]) == code
    err = capsys.readouterr().err.strip()
    assert err.startswith("make_dataset: ") and "\n" not in err and "SIG" in err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    "args,message",
    [
        (["--frames-per-axis", "0"], "--frames-per-axis"),
        (["--frames-per-axis", "-5"], "--frames-per-axis"),
        (["--frames-per-axis", "1.5"], "--frames-per-axis"),
        (["--axes", "x", "x"], "'x' is given twice"),
        (["--amplitudes-nmm", "nan"], "--amplitudes-nmm"),
        (["--amplitudes-nmm", "-20"], "--amplitudes-nmm"),
        (["--seed", "-1"], "--seed"),
    ],
)
def test_make_dataset_refuses_nonsense_arguments(tmp_path, capsys, args, message):
    with pytest.raises(SystemExit) as stop:
        make_dataset_main([str(tmp_path / "d"), *args])
    assert stop.value.code == 2 and message in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    "make_out,message",
    [
        (lambda t: t / "exists", "already exists"),
        (lambda t: Path("/proc/none/d"), "cannot write in"),
        (lambda t: t / "file" / "d", "is a file"),
        (lambda t: Path("/dev/full"), "already exists"),
    ],
)
def test_make_dataset_checks_out_before_any_work(tmp_path, capsys, monkeypatch, make_out, message):
    import evaluation.offline.make_dataset_cli as cli

    (tmp_path / "exists").mkdir()
    (tmp_path / "file").write_text("")
    monkeypatch.setattr(cli, "write_jig_dataset", lambda *a, **k: pytest.fail("work began"))
    assert make_dataset_main([str(make_out(tmp_path))]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("make_dataset: error:") and message in err and "\n" not in err


def test_zeroed_on_the_grasp_the_estimator_sees_the_open_gel(dataset_folder, monkeypatch):
    """A dataset with an ``open`` interval hands its frames to the estimator as the open gel
    (before the grasp reference); zeroed on the open interval itself it does not."""
    from controller.offline.dataset_fit import estimate_dataset
    from controller.tactile import estimator_for_sensor
    from controller.tactile.estimator import TactileEstimator

    dataset = Dataset(dataset_folder)
    seen = []
    original = TactileEstimator.set_open_reference

    def spy(self, frames):
        seen.append(None if frames is None else len(frames))
        return original(self, frames)

    monkeypatch.setattr(TactileEstimator, "set_open_reference", spy)
    estimator = estimator_for_sensor("gelsight_mini", "default")
    estimate_dataset(dataset, estimator)
    assert seen == [int(dataset.in_interval(dataset.meta.open).sum())] and seen[0] > 0
    assert estimator.contact_centre_mm is not None
    estimate_dataset(dataset, estimator, zero_on="open")
    assert seen[-1] is None and estimator.contact_centre_mm is None
