"""``python -m evaluation success_chart``: success against time charted from finished batch
folders, the same seeds for every curve, bad input refused in one line."""

from __future__ import annotations

import csv
import dataclasses
from pathlib import Path

from controller.run.result import TrialResult
from evaluation.trials.batch import _csv_row
from evaluation.trials.success_chart_cli import main


def _result(seed: int, controller: str, success: bool) -> TrialResult:
    base = TrialResult("usb_c", controller, seed, True, "inserted", None, 9.0, 12.0, 1.0, 20.0, 5.0)
    if success:
        return dataclasses.replace(base, time_to_insert_s=5.0 + seed)
    return dataclasses.replace(base, success=False, status="failed", failure_reason="timeout")


def _batch(folder: Path, controller: str, seeds: range, inserted: set[int]) -> Path:
    folder.mkdir(parents=True)
    rows = [_csv_row(_result(s, controller, s in inserted)) for s in seeds]
    with open(folder / "trials.csv", "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    return folder


def test_each_batch_is_a_curve_of_the_same_seeds(tmp_path, capsys):
    a = _batch(tmp_path / "a", "dipole", range(0, 6), {0, 1, 2, 3})
    b = _batch(tmp_path / "b", "blind", range(0, 4), {1})
    out = tmp_path / "chart.png"
    assert main([str(a), f"{b}=blind at 2 N", "--seeds", "0:4", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "dipole: 4/4 inserted" in printed and "blind at 2 N: 1/4 inserted" in printed
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    before = (a / "trials.csv").read_bytes()
    assert main([str(a), str(b), "--out", str(tmp_path / "other.png")]) == 2  # other seeds
    assert "holds other seeds" in capsys.readouterr().err
    assert (a / "trials.csv").read_bytes() == before and not (tmp_path / "other.png").exists()


def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys):
    a = _batch(tmp_path / "a", "dipole", range(0, 2), {0})
    cases = [
        ([str(tmp_path / "none"), "--out", str(tmp_path / "c.png")], "holds no trials.csv"),
        ([str(a), "--seeds", "0:3", "--out", str(tmp_path / "c.png")], "no trial of seed 2"),
        ([str(a), str(a), "--out", str(tmp_path / "c.png")], "two curves are labelled dipole"),
        ([str(a), "--out", str(a)], "is a folder"),
    ]
    for args, message in cases:
        assert main(args) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and message in err, err
    assert not (tmp_path / "c.png").exists()
