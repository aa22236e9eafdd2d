"""The near misses' sides, measured on a made-up record whose torque names the side."""

import json

import numpy as np
import pytest

from evaluation.trials import near_miss_sides
from evaluation.trials.near_miss_sides import record_cosines

OPENING = {"width_m": 0.00834, "height_m": 0.00256, "depth_m": 0.0065}
PLUG = {"width_m": 0.00825, "thickness_m": 0.0024, "length_m": 0.02}


def _record(folder, tip_x_m, torque_change_nm):
    """40 sweep ticks at 100 Hz; from tick 30 the tip is ``tip_x_m`` off the opening's centre
    along its width and the gel's torque about B's axes has changed by
    ``torque_change_nm`` (the plug upright, S = B)."""
    folder.mkdir()
    n = 40
    t = np.arange(n) * 0.01
    tip = np.zeros((n, 3))
    tip[30:, 0] = tip_x_m
    tip[:30, 0] = 0.02  # far from the opening before
    wrench = np.zeros((n, 6))
    wrench[30:, 3:6] = torque_change_nm
    np.savez(
        folder / "truth.npz",
        t_s=t,
        tip_xyz_b=tip,
        depth_m=np.zeros(n),
        plug_quat_b=np.tile([1.0, 0, 0, 0], (n, 1)),
        gel_wrench_s=wrench,
        hole_x_m=0.0,
        hole_y_m=0.0,
        hole_yaw_rad=0.0,
    )
    ticks = [
        {
            "t_s": float(ti),
            "stage": "search.sweep",
            "estimate_t_s": float(ti),
            "estimate": dict(zip(("tau_x", "tau_y", "tau_z"), map(float, w[3:6]), strict=True)),
        }
        for ti, w in zip(t, wrench, strict=True)
    ]
    (folder / "ticks.jsonl").write_text("\n".join(json.dumps(k) for k in ticks) + "\n")
    config = {"scene": {"receptacle": OPENING}, "plug": PLUG}
    (folder / "trial.json").write_text(json.dumps({"config": config}))
    return folder


def test_a_torque_along_the_supported_side_agrees(tmp_path):
    # the tip +2 mm along x: the board bears the face's +x part; the gel's torque on the
    # plug changes along -(u x z) = -((1,0,0) x (0,0,1)) = (0, 1, 0)
    record = _record(tmp_path / "r", 0.002, [0.0, 0.003, 0.0])
    cos = record_cosines(record, 0.0015)
    assert cos[("truth", "width")] and min(cos[("truth", "width")]) == pytest.approx(1.0)
    assert cos[("estimate", "width")] and min(cos[("estimate", "width")]) == pytest.approx(1.0)
    assert not cos[("truth", "thickness")]


def test_the_opposite_torque_opposes_and_a_small_change_is_not_counted(tmp_path):
    cos = record_cosines(_record(tmp_path / "r", 0.002, [0.0, -0.003, 0.0]), 0.0015)
    assert max(cos[("truth", "width")]) == pytest.approx(-1.0)
    small = record_cosines(_record(tmp_path / "s", 0.002, [0.0, 0.001, 0.0]), 0.0015)
    assert not any(small.values())


def test_a_folder_without_a_record_is_one_line_and_exit_2(tmp_path, capsys):
    assert near_miss_sides.main([str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(tmp_path) in err[0]


def test_the_table_counts_each_signal(tmp_path, capsys):
    _record(tmp_path / "r", -0.002, [0.0, -0.003, 0.0])  # -x: the change along (0, -1, 0)
    assert near_miss_sides.main([str(tmp_path / "r")]) == 0
    table = capsys.readouterr().out
    assert "| truth | width |" in table and "+1.00 |" in table
