"""``python -m evaluation grasp_scores``: FEEL's estimate scored from finished batch folders,
a table and a histogram per batch, an older table's tip offset derived, bad input refused."""

from __future__ import annotations

import csv
import dataclasses
import json
import math
from pathlib import Path

import pytest

from controller.run.result import TrialResult
from evaluation.trials.batch import _csv_row
from evaluation.trials.grasp_scores_cli import main

USB_C_PLUG_M = 0.020  # configs/tasks: the USB-C plug's length from the TCP to its tip


def _result(seed: int, controller: str = "dipole", estimate: float = math.nan) -> TrialResult:
    base = TrialResult("usb_c", controller, seed, True, "inserted", None, 9.0, 12.0, 1.0, 20.0, 5.0)
    return dataclasses.replace(
        base,
        grasp_tilt_true_rad=0.03,
        grasp_tilt_thickness_true_rad=0.05,
        grasp_tilt_thickness_est_rad=estimate,
        tip_y_est_m=USB_C_PLUG_M * math.sin(estimate),
        tip_x_true_m=0.001,
        tip_y_true_m=USB_C_PLUG_M * math.sin(0.05),
    )


def _batch(folder: Path, results: list[TrialResult], drop: tuple[str, ...] = ()) -> Path:
    """A batch folder: its trials.csv (without the columns ``drop``) and batch.json."""
    folder.mkdir(parents=True)
    rows = [{k: v for k, v in _csv_row(r).items() if k not in drop} for r in results]
    with open(folder / "trials.csv", "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    plan = {"task": "usb_c", "controller": results[0].controller, "seeds": "0:4", "overrides": []}
    (folder / "batch.json").write_text(json.dumps(plan))
    return folder


RESULTS = [_result(0, estimate=0.06), _result(1, estimate=0.03), _result(2), _result(3)]


def test_a_batch_gets_its_table_histogram_and_block(tmp_path, capsys):
    batch = _batch(tmp_path / "c_dipole", RESULTS)
    out = tmp_path / "scores"
    assert main([str(batch), "--out", str(out)]) == 0
    table = (out / "grasp_scores.md").read_text()
    assert capsys.readouterr().out == table
    row = "| usb_c, dipole, seeds 0:4 (`c_dipole`) | tilt about T x (thickness plane), deg | 2/4 |"
    assert f"{row} {math.degrees(0.015):.2f} |" in table  # |0.01| and |-0.02| rad: median 0.015
    assert "| tip offset along T y, mm | 2/4 |" in table
    assert "| tilt about T y (width plane), deg | not estimated | (1.72) |" in table
    assert "derived" not in table
    assert (out / "grasp_errors_c_dipole.png").stat().st_size > 1000
    block = json.loads((out / "grasp_scores.json").read_text())["c_dipole"]["grasp_estimate"]
    assert set(block["errors"]) == {"thickness_tilt_deg", "tip_y_mm"}
    assert block["errors"]["tip_y_mm"]["n"] == 2


def test_an_older_table_gets_the_tip_offset_from_the_tilt_and_says_so(tmp_path, capsys):
    new = _batch(tmp_path / "new", RESULTS)
    old = _batch(tmp_path / "old", RESULTS, drop=("tip_y_est_m",))
    assert main([str(new), str(old), "--out", str(tmp_path / "scores")]) == 0
    scores = json.loads((tmp_path / "scores" / "grasp_scores.json").read_text())
    # derived as the machine computes it: the same errors as the recorded column's
    old_block, new_block = (scores[k]["grasp_estimate"] for k in ("old", "new"))
    assert old_block["errors"]["tip_y_mm"] == pytest.approx(new_block["errors"]["tip_y_mm"])
    assert old_block["errors"]["tip_y_mm"]["n"] == 2
    table = capsys.readouterr().out
    assert "`old`: its trials.csv has no `tip_y_est_m`" in table and "L = 20 mm" in table
    assert "`new`: its" not in table


def test_a_batch_without_an_estimate_is_a_row_that_says_so(tmp_path, capsys):
    blind = _batch(tmp_path / "blind", [_result(0, "blind"), _result(1, "blind")])
    assert main([str(blind), "--out", str(tmp_path / "scores")]) == 0
    assert "| every quantity | no estimate of 2 |" in capsys.readouterr().out
    assert not list((tmp_path / "scores").glob("*.png"))


def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys):
    batch = _batch(tmp_path / "b", RESULTS)
    assert main([str(tmp_path / "missing"), "--out", str(tmp_path / "o")]) == 2
    assert "is not a folder" in capsys.readouterr().err
    (tmp_path / "empty").mkdir()
    assert main([str(tmp_path / "empty"), "--out", str(tmp_path / "o")]) == 2
    assert "holds no trials.csv" in capsys.readouterr().err
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "trials.csv").write_text("a,b\n1,2\n")
    assert main([str(tmp_path / "other"), "--out", str(tmp_path / "o")]) == 2
    assert "not a trials.csv of this version" in capsys.readouterr().err
    assert main([str(batch), "--out", str(batch / "scores")]) == 2  # never inside an input
    err = capsys.readouterr().err
    assert err.startswith("grasp_scores: error:") and err.count("\n") == 1
    assert not (batch / "scores").exists()
    twin = _batch(tmp_path / "x" / "b", RESULTS)
    assert main([str(batch), str(twin), "--out", str(tmp_path / "o")]) == 2
    assert "two batch folders are named b" in capsys.readouterr().err
