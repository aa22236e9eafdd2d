"""python -m evaluation draw_failures: a batch's failures against the scene's per-seed draws."""

import csv
import json
import math

from controller.run.result import TrialResult
from controller.run.task import load_task
from drivers.sim.scenes.insertion.draws import draw_scene
from evaluation.trials.batch import CSV_COLUMNS
from evaluation.trials.draw_failures import binned, main

SEEDS = range(40)
YAW_LIMIT_DEG = 1.5


def _yaw_deg(seed: int) -> float:
    task = load_task("usb_c", with_calibration=False)
    draw = draw_scene(task.config.hole, task.scene, seed)
    return abs(math.degrees(draw.hole.yaw_rad - task.config.hole.yaw_rad))


def _batch(folder, failed_if, overrides=()):
    folder.mkdir(parents=True)
    plan = {"task": "usb_c", "controller": "dipole", "seeds": "0:40", "overrides": list(overrides)}
    (folder / "batch.json").write_text(json.dumps(plan))
    with open(folder / "trials.csv", "w", newline="") as handle:
        writer = csv.DictWriter(handle, CSV_COLUMNS)
        writer.writeheader()
        for seed in SEEDS:
            ok = not failed_if(seed)
            result = TrialResult(
                "usb_c",
                "dipole",
                seed,
                ok,
                "inserted" if ok else "failed",
                None if ok else "timeout",
                10.0 if ok else None,
                30.0,
                1.0,
                20.0,
                1.0,
            )
            writer.writerow(result.as_row())


def _row(text, name):
    return next(line for line in text.splitlines() if line.startswith(f"| {name} |"))


def test_failures_drawn_by_the_hole_yaw_fill_the_top_yaw_bins_only(tmp_path, capsys):
    _batch(tmp_path / "b", lambda seed: _yaw_deg(seed) > YAW_LIMIT_DEG)
    assert main([str(tmp_path / "b")]) == 0
    text = capsys.readouterr().out
    cells = _row(text, "hole yaw deg (abs)").split("|")[2:-1]
    first, last = cells[0].split(": ")[1], cells[-1].split(": ")[1]
    failed, trials = map(int, first.split("/"))
    assert failed == 0 and trials > 0  # every yaw under 0.75 deg inserted
    failed, trials = map(int, last.split("/"))
    assert failed == trials > 0  # every yaw over 2.25 deg failed
    expected = sum(_yaw_deg(s) > YAW_LIMIT_DEG for s in SEEDS)
    assert f"{expected} of 40 trials failed" in text


def test_a_comparisons_cells_each_get_a_table(tmp_path, capsys):
    _batch(tmp_path / "cmp" / "cells" / "dipole" / "0.004", lambda seed: seed % 2 == 0)
    _batch(tmp_path / "cmp" / "cells" / "oracle" / "0.004", lambda seed: False)
    assert main([str(tmp_path / "cmp"), "--bins", "2"]) == 0
    text = capsys.readouterr().out
    assert text.count("### usb_c") == 2 and "20 of 40 trials failed" in text
    assert "0 of 40 trials failed" in text
    assert len(_row(text, "reach shortfall mm").split("|")) == 2 + 2 + 1


def test_the_overrides_the_batch_ran_with_draw_the_same_scene(tmp_path, capsys):
    # with no yaw uncertainty every hole yaw is nominal: one value, all in the first bin
    _batch(tmp_path / "b", lambda seed: False, ["scene.hole_uncertainty.yaw_rad=0"])
    assert main([str(tmp_path / "b")]) == 0
    assert "+0.00..+0.00: 0/40" in _row(capsys.readouterr().out, "hole yaw deg (abs)")


def test_bins_cover_the_range_with_the_top_edge_in_the_last():
    counts = binned([0.0, 1.0, 2.0, 4.0], [False, True, False, True], 2)
    assert [(c.low, c.high, c.failed, c.trials) for c in counts] == [
        (0.0, 2.0, 1, 2),
        (2.0, 4.0, 1, 2),
    ]


def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys):
    assert main([str(tmp_path / "missing")]) == 2
    assert "is not a folder" in capsys.readouterr().err
    assert main([str(tmp_path)]) == 2
    assert "holds no batch.json" in capsys.readouterr().err
    (tmp_path / "x").mkdir()
    (tmp_path / "x" / "batch.json").write_text("{not json")
    assert main([str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "not a batch plan" in err
    _batch(tmp_path / "u", lambda seed: False)
    (tmp_path / "u" / "batch.json").write_text(json.dumps({"task": "usb_z"}))
    assert main([str(tmp_path / "u")]) == 2
    assert "usb_z" in capsys.readouterr().err


def _grasp_tilt_x_deg(seed: int) -> float:
    task = load_task("usb_c", with_calibration=False)
    return math.degrees(draw_scene(task.config.hole, task.scene, seed).grasp.tilt_x_rad)


def test_failures_on_one_side_of_the_grasp_tilt_show_in_its_signed_row_only(tmp_path, capsys):
    _batch(tmp_path / "b", lambda seed: _grasp_tilt_x_deg(seed) < 0.0)
    assert main([str(tmp_path / "b"), "--bins", "2"]) == 0
    text = capsys.readouterr().out
    low, high = (cell.split(": ") for cell in _row(text, "grasp tilt x deg").split("|")[2:-1])
    assert float(low[0].split("..")[0]) < 0.0 < float(high[0].split("..")[1])
    failed, trials = map(int, high[1].split("/"))
    assert failed == 0 < trials  # every positive tilt inserted
    # the absolute row mixes both signs in its bins
    assert all(
        0 < int(c.split(": ")[1].split("/")[0])
        for c in _row(text, "grasp tilt x deg (abs)").split("|")[2:-1]
    )
