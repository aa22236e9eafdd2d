"""The plug's true pose in the hand in the machine's terms (evaluation/trials/grasp_truth.py),
against which FEEL's estimate is scored, and the trial table's pose columns."""

import dataclasses
import math

import pytest

from controller.run.result import TrialResult
from drivers.sim.scenes.insertion.draws import GraspPose
from evaluation.trials.grasp_scores import chart_errors, quantity, signed_errors, table_cells
from evaluation.trials.grasp_truth import grasp_truth, receptacle_tilts_rad
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


def test_the_receptacle_tilts_in_each_plane_with_the_board_about_its_axis():
    # the board turned by b about H x turns the receptacle's axis by -b about T x (T y = -H y),
    # the width plane unchanged
    assert receptacle_tilts_rad((0.01, 0.0)) == pytest.approx((0.0, -0.01), abs=1e-12)
    # about H y by b: the axis (-sin b, 0, -cos b) in H is (-sin b, 0, cos b) in T, -b about T y
    assert receptacle_tilts_rad((0.0, 0.02)) == pytest.approx((-0.02, 0.0), abs=1e-12)
    assert receptacle_tilts_rad((0.0, 0.0)) == (0.0, 0.0)


def test_a_table_without_the_pose_columns_reads_them_as_unknown():
    result = TrialResult("usb_c", "dipole", 3, True, "inserted", None, 9.0, 12.0, 1.0, 20.0, 5.0)
    row = {
        k: ("" if v is None else repr(v) if isinstance(v, float) else str(v))
        for k, v in result.as_row().items()
        if not k.startswith(("grasp_", "tip_"))
    }
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
    assert set(block["errors"]) == {"width_tilt_deg", "tip_x_mm"}
    tilt = block["errors"]["width_tilt_deg"]
    assert tilt["n"] == 2 and tilt["median"] == pytest.approx(math.degrees(0.015))
    assert tilt["max"] == pytest.approx(math.degrees(0.02))
    assert block["errors"]["tip_x_mm"]["median"] == pytest.approx(0.4)
    # the thickness plane is not estimated here: its true size, for scale
    assert set(block["not_estimated"]) == {"thickness_tilt_deg", "tip_y_mm"}
    assert block["not_estimated"]["thickness_tilt_deg"]["median"] == pytest.approx(
        math.degrees(0.01)
    )
    assert block["not_estimated"]["tip_y_mm"]["n"] == 3


def _with_thickness(seed: int, est: float, true: float, tip_est: float, tip_true: float):
    base = TrialResult("usb_c", "dipole", seed, True, "inserted", None, 9.0, 12.0, 1.0, 20.0, 5.0)
    return dataclasses.replace(
        base,
        grasp_tilt_true_rad=0.02,
        grasp_tilt_thickness_est_rad=est,
        grasp_tilt_thickness_true_rad=true,
        tip_y_est_m=tip_est,
        tip_y_true_m=tip_true,
        tip_x_true_m=-0.0003,
    )


def test_the_thickness_plane_is_scored_where_it_is_estimated_and_errors_are_signed():
    results = [
        _with_thickness(0, 0.03, 0.02, 0.0006, 0.0004),  # +0.573 deg, +0.2 mm
        _with_thickness(1, 0.00, 0.04, 0.0, 0.0008),  # -2.29 deg, -0.8 mm
        _with_thickness(2, math.nan, 0.05, math.nan, 0.001),  # FEEL did not run
        _with_thickness(3, 0.01, 0.01, math.nan, 0.0),  # an older table: no tip estimate
    ]
    block = summarize(results)["grasp_estimate"]
    assert (block["estimated"], block["of"]) == (3, 4)
    assert set(block["errors"]) == {"thickness_tilt_deg", "tip_y_mm"}
    tilt = block["errors"]["thickness_tilt_deg"]
    assert tilt["n"] == 3 and tilt["max"] == pytest.approx(math.degrees(0.04))
    assert tilt["median"] == pytest.approx(math.degrees(0.01))
    assert block["errors"]["tip_y_mm"]["n"] == 2
    assert block["errors"]["tip_y_mm"]["max"] == pytest.approx(0.8)
    assert set(block["not_estimated"]) == {"width_tilt_deg", "tip_x_mm"}
    assert block["not_estimated"]["tip_x_mm"]["median"] == pytest.approx(0.3)
    signed = signed_errors(results, quantity("thickness_tilt_deg"))
    assert signed == pytest.approx([math.degrees(0.01), -math.degrees(0.04), 0.0])
    assert chart_errors(results)["tip offset along T y, mm"] == pytest.approx([0.2, -0.8])
    rows = table_cells(block)
    assert rows[0][:2] == ["tilt about T x (thickness plane), deg", "3/4"]
    assert rows[1][:2] == ["tip offset along T y, mm", "2/4"]
    assert rows[2][:2] == ["tilt about T y (width plane), deg", "not estimated"]
    assert rows[2][2] == f"({math.degrees(0.02):.2f})"


def test_both_planes_are_scored_when_both_are_estimated():
    both = dataclasses.replace(
        _with_thickness(0, 0.01, 0.0, 0.0002, 0.0),
        grasp_tilt_est_rad=0.03, tip_x_est_m=0.0001, tip_x_true_m=0.0,
    )  # fmt: skip
    block = summarize([both])["grasp_estimate"]
    assert list(block["errors"]) == ["thickness_tilt_deg", "tip_y_mm", "width_tilt_deg", "tip_x_mm"]
    assert block["not_estimated"] == {} and block["estimated"] == 1


def test_a_controller_without_an_estimate_has_no_block():
    assert "grasp_estimate" not in summarize([_with_pose(0, math.nan, 0.01, math.nan, 0.0)])
