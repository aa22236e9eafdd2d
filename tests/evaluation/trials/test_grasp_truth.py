"""The plug's true pose in the hand in the machine's terms (evaluation/trials/grasp_truth.py),
against which FEEL's estimate is scored, and the trial table's pose columns."""

import dataclasses
import math

import pytest

from controller.run.result import TrialResult
from drivers.sim.scenes.insertion.draws import GraspPose
from evaluation.trials.grasp_truth import grasp_truth
from evaluation.trials.summary import summarize


def test_a_turn_about_the_gel_normal_is_a_width_plane_tilt_of_the_other_sign():
    # z_S is -T y: turning by b about z_S turns the plug by -b about T y, its tip to -T x
    truth = grasp_truth(GraspPose(tilt_z_rad=0.05), 0.02)
    assert truth.tilt_width_rad == pytest.approx(-0.05)
    assert truth.tilt_thickness_rad == pytest.approx(0.0, abs=1e-12)
    assert truth.tip_t_m == pytest.approx([-0.02 * math.sin(0.05), 0.0, 0.02 * math.cos(0.05)])


def test_a_turn_about_the_width_axis_tilts_the_thickness_plane_only():
    truth = grasp_truth(GraspPose(tilt_x_rad=0.04), 0.02)
    assert truth.tilt_width_rad == pytest.approx(0.0, abs=1e-12)
    assert abs(truth.tilt_thickness_rad) == pytest.approx(0.04)
    assert truth.tip_t_m[0] == pytest.approx(0.0, abs=1e-12)


def test_the_offsets_move_the_tip_across_and_along():
    truth = grasp_truth(GraspPose(along_m=0.001, across_m=-0.0005), 0.02)
    assert truth.tip_t_m == pytest.approx([-0.0005, 0.0, 0.021])


def test_a_table_without_the_pose_columns_reads_them_as_unknown():
    result = TrialResult("usb_c", "dipole", 3, True, "inserted", None, 9.0, 12.0, 1.0, 20.0, 5.0)
    row = {k: ("" if v is None else repr(v) if isinstance(v, float) else str(v))
           for k, v in result.as_row().items() if not k.startswith(("grasp_", "tip_"))}
    back = TrialResult.from_row(row)
    assert math.isnan(back.grasp_tilt_est_rad) and math.isnan(back.tip_x_true_m)
    assert back.seed == 3 and back.time_to_insert_s == 9.0


def _with_pose(seed: int, est: float, true: float, tip_est: float, tip_true: float):
    base = TrialResult("usb_c", "align", seed, True, "inserted", None, 9.0, 12.0, 1.0, 20.0, 5.0)
    return dataclasses.replace(
        base,
        grasp_tilt_est_rad=est,
        grasp_tilt_true_rad=true,
        grasp_tilt_thickness_true_rad=-0.01,
        tip_x_est_m=tip_est,
        tip_x_true_m=tip_true,
        tip_y_true_m=0.0002,
    )


def test_the_summary_scores_the_estimates_in_degrees_and_millimetres():
    results = [
        _with_pose(0, 0.010, 0.0, 0.0002, 0.0),  # 0.573 deg, 0.2 mm
        _with_pose(1, 0.0, 0.020, 0.0, 0.0006),  # 1.146 deg, 0.6 mm
        _with_pose(2, math.nan, 0.03, math.nan, 0.0),  # no estimate
    ]
    block = summarize(results)["grasp_estimate"]
    assert (block["estimated"], block["of"]) == (2, 3)
    assert block["tilt_error_deg"]["median"] == pytest.approx(math.degrees(0.015))
    assert block["tilt_error_deg"]["max"] == pytest.approx(math.degrees(0.02))
    assert block["tip_x_error_mm"]["median"] == pytest.approx(0.4)
    assert block["thickness_tilt_deg_not_estimated"]["median"] == pytest.approx(
        math.degrees(0.01)
    )


def test_a_controller_without_an_estimate_has_no_block():
    assert "grasp_estimate" not in summarize([_with_pose(0, math.nan, 0.01, math.nan, 0.0)])
