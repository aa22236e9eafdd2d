"""Dataset format round trip, its errors, and scripts/calibrate.py on a small simulated jig
dataset."""

from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml

from controller.tactile.calibration import Calibration
from drivers.config import ConfigError
from drivers.sim.render.marker_images import MarkerImageRenderer
from drivers.sim.scenes.jig import Experiment
from evaluation.jig_dataset import write_jig_dataset
from evaluation.offline.calibrate_cli import main as calibrate_main
from evaluation.offline.dataset import META, Dataset
from evaluation.sim_setup import gel_model, jig_config


class _ExactRenderer:
    """The exact spline renderer behind the FrameRenderer interface (full-size field)."""

    def __init__(self) -> None:
        self._renderer = MarkerImageRenderer(rng=np.random.default_rng(2))

    def render(self, displacement_px: np.ndarray, *, frame_index: int) -> np.ndarray:
        full = cv2.resize(displacement_px.astype(np.float32), (320, 240))
        return self._renderer.render(full)


@pytest.fixture(scope="module")
def dataset_folder(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("jig") / "plate"
    config = jig_config()
    write_jig_dataset(
        folder,
        "gelsight_mini",
        gel_model("gelsight_mini", "plate"),
        _ExactRenderer(),
        [Experiment("x", 0.04, 4)],
        config,
        seed=5,
    )
    return folder


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
