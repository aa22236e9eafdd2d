"""The origin study of the real-gel check (evaluation/realgel/origins.py): the contact's
centroid is where the push stops leaking into the tilt, on the true field."""

import numpy as np
import pytest

from controller.tactile.settings import estimator_config
from evaluation.realgel import origins_cli
from evaluation.realgel.origins import (
    contact_centroid_mm,
    origin_scores,
    support_centroid,
    with_dipole_grid,
)
from evaluation.realgel.sequences import SequenceSpec, mechanics


def test_the_contact_centroid_is_in_frame_s():
    spec = SequenceSpec("gelsight_markers_a", "x", 0.4, 0.4, 2.0, seed=5, frames=8)
    mech = mechanics(spec)
    patch_x = float((mech.basis.uniform * np.arange(320)).sum() / mech.basis.uniform.sum())
    cx, _ = contact_centroid_mm(mech, 0.1)
    assert cx == pytest.approx((patch_x + 0.5 - 160) * 0.1)


def test_the_support_centroid_of_a_box_is_its_centre_and_zero_for_no_divergence():
    x, y = (v.ravel() for v in np.meshgrid(np.arange(8.0), np.arange(6.0)))
    div = np.where((x >= 2) & (x <= 5) & (y >= 1) & (y <= 2), 3.0, 0.0)
    assert support_centroid(0.3)(div, x, y) == pytest.approx((3.5, 1.5))
    assert support_centroid(0.3)(np.zeros_like(x), x, y) == (0.0, 0.0)


def test_about_the_contact_centroid_the_push_does_not_leak_into_the_tilt():
    spec = SequenceSpec("gelsight_markers_a", "y", 0.45, 0.4, 2.0, seed=3, frames=32)
    config = with_dipole_grid(estimator_config("default"), "field")
    scores = origin_scores(spec, config)
    assert scores["contact"] > 0.99
    assert scores["gel centre"] < scores["contact"] - 0.05
    assert scores["contact +0.5 mm"] < scores["contact"]


def test_the_cli_prints_a_row_per_configuration_and_pushing_sequence(capsys):
    assert origins_cli.main(["--estimators", "default", "--frames", "8", "--seed", "1"]) == 0
    rows = [line for line in capsys.readouterr().out.splitlines() if line.startswith("| default")]
    assert len(rows) == 2


@pytest.mark.parametrize(
    "args, message",
    [
        (["--dipole-grids", "5by4"], "--dipole-grids '5by4'"),
        (["--estimators", "nope"], "--estimators"),
        (["--frames", "2"], "--frames 2"),
    ],
)
def test_bad_arguments_exit_2_naming_the_input(args, message, capsys):
    with pytest.raises(SystemExit) as exit_info:
        origins_cli.main(args)
    assert exit_info.value.code == 2
    assert message in capsys.readouterr().err
