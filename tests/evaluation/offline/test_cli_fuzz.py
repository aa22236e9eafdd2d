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

from controller.cli.calibrate import main as calibrate_main
from controller.cli.estimate import main as estimate_main
from controller.tactile.calibration import AxisFit, Calibration, estimator_sha256
from controller.tactile.settings import sensor_estimator
from core.sensor_profile import sensor_profile
from drivers.sim.scenes.jig import Experiment
from evaluation.common.rendering import make_renderer
from evaluation.common.sim_setup import gel_model, jig_config
from evaluation.offline.jig_dataset import write_jig_dataset
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


WORD = st.one_of(
    st.sampled_from(PATHS), st.sampled_from(VALUES), st.text(alphabet=SAFE, max_size=6)
)


def option(flag: str, plausible: list[str], required: bool = False):
    """``flag`` with a plausible value or any word, or (unless ``required``, then rarely)
    absent. Plausible values are drawn often, so that runs get past the first checks and
    reach the later ones."""
    value = st.one_of(*[st.sampled_from(plausible)] * 4, WORD)
    given_ = value.map(lambda v: [flag, v])
    absent = st.just([])
    return st.one_of(given_, given_, given_, absent) if required else st.one_of(given_, absent)


def command(first: list[str], options: list, switches: list[str]):
    """An argument list: a first argument, options in random order, switches, stray words."""
    parts = st.tuples(
        st.sampled_from(first).map(lambda v: [v]),
        st.permutations(options).flatmap(lambda opts: st.tuples(*opts)),
        st.lists(st.sampled_from(switches), max_size=2),
        st.one_of(st.just([]), st.just([]), st.just([]), st.lists(WORD, min_size=1, max_size=2)),
    )
    return parts.map(lambda p: p[0] + [w for o in p[1] for w in o] + p[2] + p[3])


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

ESTIMATE_ARGS = command(
    ["frames", "clip.avi", *PATHS],
    [
        option("--out", ["out.csv", "o/x.csv"], required=True),
        option("--reference", ["0", "0:2", "1:3"]),
        option("--sensor", ["gelsight_mini", "digit"]),
        option("--method", ["default", "dis_ultrafast"]),
        option("--calibration", ["cal.yaml", "binary.yaml", "text.yaml"]),
        option("--fps", ["25", "1e-300", "nan"]),
    ],
    ["--force", "--allow-damaged", "--force", "--allow-damaged", "--help"],
)


@FUZZ
@given(args=ESTIMATE_ARGS)
def test_estimate_exits_0_or_2_on_any_arguments(sandbox, capsys, args):
    code = exit_code(estimate_main, args)
    err = capsys.readouterr().err
    assert code in (0, 2), (args, err)
    assert "Traceback" not in err
    assert (sandbox / "clip.avi").stat().st_size > 0 and len(list(sandbox.glob("frames/*"))) == 4


CALIBRATE_ARGS = command(
    ["dataset", *PATHS],
    [
        option("--out", ["out/cal.yaml", "cal2.yaml"]),
        option("--method", ["default", "dis_ultrafast", "binary.yaml"]),
    ],
    ["--help"],
)


@settings(FUZZ, max_examples=int(os.environ.get("FUZZ_EXAMPLES", "40")))
@given(args=CALIBRATE_ARGS)
def test_calibrate_exits_0_or_2_on_any_arguments(sandbox, capsys, args):
    code = exit_code(calibrate_main, args)
    err = capsys.readouterr().err
    assert code in (0, 2), (args, err)
    assert "Traceback" not in err
    assert (sandbox / "dataset" / "meta.yaml").is_file()
