"""``python -m evaluation fit_imprint_gain``: the imprint's gain fitted on finished batches
and checked on others; bad input refused in one line."""

from __future__ import annotations

import dataclasses
import math

import pytest

from controller.run.result import TrialResult
from controller.run.task import load_task
from evaluation.trials.imprint_gain_cli import main
from tests.evaluation.trials.test_grasp_scores_cli import _batch


def _result(seed: int, true_m: float, read_m: float) -> TrialResult:
    """A trial whose machine read the centre ``read_m`` with the task's gain."""
    base = TrialResult("usb_c", "dipole", seed, True, "inserted", None, 9.0, 12.0, 1.0, 20.0, 5.0)
    return dataclasses.replace(base, imprint_true_m=true_m, imprint_offset_est_m=read_m / GAIN)


GAIN = load_task("usb_c").config.touch_spiral.imprint_gain


def test_the_gain_is_the_slope_and_the_check_reports_the_offsets_error(tmp_path, capsys):
    truths = [-0.0009, -0.0004, 0.0002, 0.0008]
    fit = _batch(tmp_path / "fit", [_result(k, t, 0.5 * t) for k, t in enumerate(truths)])
    unread = _result(9, 0.0005, math.nan)  # a trial that read none is left out
    check = _batch(tmp_path / "check", [_result(4, 0.001, 0.0006), unread])
    assert main(["--fit", str(fit), "--check", str(check)]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0] == "imprint_gain: 0.5000"
    # 0.6 mm / 0.5 = 1.2 mm read for 1 mm: 0.2 mm off
    assert out[1] == (
        "offset error on 1 checked trials: RMS 0.200 mm, median 0.200 mm, largest 0.200 mm"
    )


@pytest.mark.parametrize("case", ["overlap", "unread", "missing"])
def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys, case):
    fit = _batch(tmp_path / "fit", [_result(0, 0.001, 0.0005)])
    unread = _batch(tmp_path / "unread", [_result(1, 0.001, math.nan)])
    check = {"overlap": fit, "unread": unread, "missing": tmp_path / "nothing"}[case]
    assert main(["--fit", str(fit), "--check", str(check)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    assert {"overlap": "in both", "unread": "no trial read", "missing": "batch.json"}[case] in err
