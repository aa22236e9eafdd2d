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


def _on_a_tilted_board(seed: int, board_rad: float, rock_error_rad: float) -> TrialResult:
    """A trial whose FEEL read the plug against the receptacle's axis, off by
    ``rock_error_rad``, on a board tilted by ``board_rad`` in the thickness plane."""
    tilt, against_receptacle = 0.05, 0.05 + board_rad
    estimate = against_receptacle + rock_error_rad
    return dataclasses.replace(
        _result(seed, estimate=estimate), thickness_tilt_to_receptacle_true_rad=against_receptacle,
        tip_y_true_m=USB_C_PLUG_M * math.sin(tilt),
    )  # fmt: skip


def _board_shares(out: Path, name: str) -> dict:
    """The ``board_share`` block of batch ``name`` in ``out``'s grasp_scores.json."""
    return json.loads((out / "grasp_scores.json").read_text())[name]["board_share"]


def _assert_the_board_explains_it_all(share: dict, n: int, board_median_rad: float) -> None:
    """An estimate exact against the receptacle's axis: its error is all the board's."""
    assert share["n"] == n
    assert share["board_tilt_median_deg"] == pytest.approx(math.degrees(board_median_rad))
    assert share["correlation"] == pytest.approx(1.0)
    assert share["tip_error_less_board_median_mm"] == pytest.approx(0.0, abs=1e-9)


def test_the_board_share_names_the_error_that_the_board_tilt_makes(tmp_path, capsys):
    boards = [0.004, -0.012, 0.008, -0.016, 0.01]
    exact = [_on_a_tilted_board(i, b, 0.0) for i, b in enumerate(boards)]
    assert main([str(_batch(tmp_path / "exact", exact)), "--out", str(tmp_path / "s")]) == 0
    table = capsys.readouterr().out
    shares = _board_shares(tmp_path / "s", "exact")
    assert shares["width"] is None  # no width-plane estimate
    _assert_the_board_explains_it_all(shares["thickness"], 5, 0.01)
    assert "`exact`: the board's tilt about T x" in table and "correlation 1.00" in table
    # a rock error of its own, unrelated to the board: the share explains little of it
    own = [0.01, 0.012, -0.015, -0.008, 0.011]
    noisy = [_on_a_tilted_board(i, b, e) for i, (b, e) in enumerate(zip(boards, own, strict=True))]
    assert main([str(_batch(tmp_path / "noisy", noisy)), "--out", str(tmp_path / "t")]) == 0
    share = _board_shares(tmp_path / "t", "noisy")["thickness"]
    assert share["correlation"] < 0.8
    assert share["tip_error_less_board_median_mm"] == pytest.approx(
        1e3 * USB_C_PLUG_M * 0.011, rel=0.05
    )  # L sin(a + b + e) - L sin(a + b) ~ L e, the median |e| 0.011 rad


def test_too_few_trials_with_both_truths_give_no_board_share(tmp_path):
    assert main([str(_batch(tmp_path / "b", RESULTS)), "--out", str(tmp_path / "s")]) == 0
    assert _board_shares(tmp_path / "s", "b") == {"thickness": None, "width": None}


def test_the_width_plane_has_its_own_board_share(tmp_path, capsys):
    # FEEL about T y exact against the receptacle's axis, the board tilted about T y: the
    # width plane's error is the board's tilt, its tip's the board's share along T x
    boards = [0.006, -0.01, 0.012, -0.004]
    tilt = 0.03  # _result's width-plane truth
    trials = [
        dataclasses.replace(
            _result(i), grasp_tilt_est_rad=tilt + b, width_tilt_to_receptacle_true_rad=tilt + b,
            tip_x_est_m=0.001 + USB_C_PLUG_M * (math.sin(tilt + b) - math.sin(tilt)),
        )
        for i, b in enumerate(boards)
    ]  # fmt: skip
    assert main([str(_batch(tmp_path / "w", trials)), "--out", str(tmp_path / "s")]) == 0
    table = capsys.readouterr().out
    shares = _board_shares(tmp_path / "s", "w")
    assert shares["thickness"] is None
    _assert_the_board_explains_it_all(shares["width"], 4, 0.008)
    assert "`w`: the board's tilt about T y" in table and "error along T x less" in table
    assert "tilt about T y from the receptacle's axis, deg | 4/4 | 0.00" in table
