"""Fuzz the offline tools' argument space: random argument lists of plausible and nonsense
tokens, run in-process. The only outcomes allowed are exit code 0 or 2 (130/143 never
happen here); any other exception is a traceback the user would have seen."""

from __future__ import annotations

import os
import string
from pathlib import Path

import cv2
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from controller.tactile.calibration import AxisFit, Calibration, estimator_sha256
from controller.tactile.settings import sensor_estimator
from drivers.config import sensor_profile
from drivers.sim.scenes.jig import Experiment
from evaluation.jig_dataset import write_jig_dataset
from evaluation.offline.calibrate_cli import main as calibrate_main
from evaluation.offline.estimate_cli import main as estimate_main
from evaluation.rendering import make_renderer
from evaluation.sim_setup import gel_model, jig_config
from tests.video_faults import write_mjpg

SAFE = string.ascii_letters + string.digits + ":.-_ ,"  # no '/', no NUL: stays in the sandbox


@pytest.fixture(scope="module")
def sandbox(tmp_path_factory):
    """A working folder with inputs of every kind; the fuzzed tools run inside it."""
    root = tmp_path_factory.mktemp("fuzz")
    renderer = make_renderer("gelsight_mini", seed=1)
    images = [renderer.render(np.zeros((12, 16, 2)), frame_index=i) for i in range(4)]
    (root / "frames").mkdir()
    for i, image in enumerate(images):
        cv2.imwrite(str(root / "frames" / f"f{i}.png"), image)
    write_mjpg(root / "clip.avi", images)
    (root / "empty").mkdir()
    (root / "text.yaml").write_text("a: [1, 2\n")
    (root / "binary.yaml").write_bytes(bytes(range(256)))
    config = sensor_estimator(sensor_profile("gelsight_mini"), "default")[1]
    fit = {"tau_x": AxisFit(0.004, 0.0, 0.001, 0.99, 100)}
    (root / "cal.yaml").write_text(
        Calibration("gelsight_mini", "default", fit, estimator_sha256(config)).to_yaml()
    )
    write_jig_dataset(
        root / "dataset",
        "gelsight_mini",
        gel_model("gelsight_mini", "plate"),
        make_renderer("gelsight_mini", seed=2),
        [Experiment("x", 0.04, 1)],
        jig_config(),
        seed=3,
    )
    previous = Path.cwd()
    os.chdir(root)
    yield root
    os.chdir(previous)


PATHS = [
    "frames",
    "clip.avi",
    "empty",
    "missing",
    "text.yaml",
    "binary.yaml",
    "cal.yaml",
    "dataset",
    "dataset/meta.yaml",
    "frames/f0.png",
    "out.csv",
    "out/x.yaml",
    "/dev/full",
    "/dev/null",
    "/proc/none/x.csv",
    ".",
    "..",
]
VALUES = [
    "0",
    "1",
    "-1",
    "0:2",
    "2:1",
    "3:99",
    "1e-300",
    "nan",
    "inf",
    "-inf",
    "25",
    "1.5",
    "",
    "default",
    "paper",
    "markers",
    "nope",
    "digit",
    "gelsight_mini",
    "digit_gel",
    "gelsight_mini_camera",
]


def tokens(flags: list[str]):
    word = st.one_of(
        st.sampled_from(flags),
        st.sampled_from(PATHS),
        st.sampled_from(VALUES),
        st.text(alphabet=SAFE, max_size=6),
    )
    return st.lists(word, max_size=9)


def exit_code(main, args: list[str]) -> int:
    try:
        return main(args)
    except SystemExit as stop:
        return 0 if stop.code is None else stop.code


FUZZ = settings(
    max_examples=int(os.environ.get("FUZZ_EXAMPLES", "60")),
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)

ESTIMATE_FLAGS = [
    "--out",
    "--reference",
    "--sensor",
    "--method",
    "--calibration",
    "--fps",
    "--force",
    "--allow-damaged",
    "-h",
]


@FUZZ
@given(first=st.sampled_from(PATHS), rest=tokens(ESTIMATE_FLAGS))
def test_estimate_exits_0_or_2_on_any_arguments(sandbox, capsys, first, rest):
    code = exit_code(estimate_main, [first, *rest])
    err = capsys.readouterr().err
    assert code in (0, 2), (first, rest, err)
    assert "Traceback" not in err
    assert (sandbox / "clip.avi").stat().st_size > 0 and len(list(sandbox.glob("frames/*"))) == 4


CALIBRATE_FLAGS = ["--out", "--method", "-h"]


@settings(FUZZ, max_examples=int(os.environ.get("FUZZ_EXAMPLES", "40")))
@given(first=st.sampled_from(PATHS), rest=tokens(CALIBRATE_FLAGS))
def test_calibrate_exits_0_or_2_on_any_arguments(sandbox, capsys, first, rest):
    code = exit_code(calibrate_main, [first, *rest])
    err = capsys.readouterr().err
    assert code in (0, 2), (first, rest, err)
    assert "Traceback" not in err
    assert (sandbox / "dataset" / "meta.yaml").is_file()
