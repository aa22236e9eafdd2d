"""The speed-accuracy front and its real-gel gate (evaluation/experiments/pareto.py)."""

import math

import pytest

from evaluation.experiments.pareto import (
    REALGEL_TARGET_R2,
    ParetoPoint,
    beating,
    front,
    worst_realgel_r2,
)
from evaluation.realgel.check import Row


def point(
    label: str, ms: float, rmse: float, realgel_r2: float = 0.99, slip: float = 0.8
) -> ParetoPoint:
    return ParetoPoint(label, ms, ms, rmse, 0.99, {"d": rmse}, realgel_r2, slip)


def row(estimator: str, r2: float) -> Row:
    nan = float("nan")
    return Row(estimator, "t", "tilt x", "x", 0.0, 0.4, 2.0, r2, nan, nan, nan, nan, 0, 0, 0)


def test_a_configuration_missing_the_real_gel_target_neither_joins_nor_blocks_the_front():
    slow_good = point("slow", 2.0, 0.4)
    fast_bad_on_real_gels = point("fast", 1.0, 0.3, realgel_r2=REALGEL_TARGET_R2 - 0.01)
    dominated = point("dominated", 3.0, 0.5)
    points = [slow_good, fast_bad_on_real_gels, dominated]
    assert [p.label for p in front(points)] == ["slow"]
    assert [p.label for p in front(points, eligible_only=False)] == ["fast"]
    assert [p.label for p in beating(points, slow_good)] == ["fast"]
    assert beating(points, fast_bad_on_real_gels) == []


def test_equal_points_do_not_beat_each_other():
    a, b = point("a", 1.0, 0.4), point("b", 1.0, 0.4)
    assert {p.label for p in front([a, b])} == {"a", "b"}


def test_worst_real_gel_r2_is_the_minimum_and_minus_inf_where_a_configuration_cannot_run():
    rows = [row("a", 0.99), row("a", 0.95), row("b", 0.99), row("b", float("nan"))]
    assert worst_realgel_r2(rows, "a") == 0.95
    assert worst_realgel_r2(rows, "b") == -math.inf
    with pytest.raises(ValueError, match="no real-gel rows"):
        worst_realgel_r2(rows, "c")


def test_slip_recall_keeps_a_configuration_on_the_eligible_front_but_not_on_the_front_of_all():
    better_slip = point("better slip", 1.5, 0.45, slip=0.85)
    better_tilt = point("better tilt", 1.4, 0.42, slip=0.71)
    assert [p.label for p in front([better_slip, better_tilt])] == ["better tilt", "better slip"]
    assert [p.label for p in front([better_slip, better_tilt], eligible_only=False)] == [
        "better tilt"
    ]
    assert beating([better_slip, better_tilt], better_slip) == []
    assert beating([better_slip, better_tilt], better_slip, with_slip=False) == [better_tilt]
