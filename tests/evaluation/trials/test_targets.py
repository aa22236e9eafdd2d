"""The product's targets judged from batch summaries (evaluation/trials/targets.py)."""

from controller.run.result import TrialResult
from evaluation.trials.summary import summarize
from evaluation.trials.targets import falls_short, targets_markdown, verdicts


def _summary(successes: int, n: int, time_s: float, violations: int = 0) -> dict:
    results = [
        TrialResult(
            "usb_c",
            "x",
            seed,
            seed < successes,
            "inserted" if seed < successes else "failed",
            None if seed < successes else "timeout",
            time_s if seed < successes else None,
            30.0,
            1.0,
            20.0,
            1.0,
            insertion_force_violations=int(seed < violations),
        )
        for seed in range(n)
    ]
    return summarize(results)


def _by_target(summaries):
    return {v.target: v for v in verdicts(summaries)}


def test_the_products_own_targets_are_judged_with_their_margins():
    judged = _by_target({"dipole": _summary(156, 200, 16.03, violations=2)})
    success = judged["`dipole` success >= 98%"]
    assert success.met is False and success.note == "by 20.0 points"
    median = judged["`dipole` median time to insert <= 15 s"]
    assert median.met is False and median.note == "by 1.03 s"
    assert judged["`dipole` 0 insertion-force violations"].met is False
    # controllers not in the grid are not judged, and say so
    assert judged["`zero_torque` falls short of `dipole`"].met is None
    assert judged["`zero_torque` falls short of `dipole`"].word == "not run"

    met = _by_target({"dipole": _summary(198, 200, 14.0)})
    assert all(met[t].met for t in met if t.startswith("`dipole`")), (
        "198/200 at 14 s with no violation meets the product's three targets"
    )


def test_falling_short_is_intervals_apart_or_a_median_30_percent_longer():
    product = _summary(150, 200, 10.0)
    assert falls_short(_summary(10, 200, 10.0), product) == (
        True,
        "the intervals do not overlap; the medians within 30%",
    )
    assert falls_short(_summary(0, 200, 10.0), product) == (True, "the intervals do not overlap")
    # overlapping intervals: only the median can decide
    assert falls_short(_summary(145, 200, 13.0), product) == (
        True,
        "the intervals overlap; its median 1.30x longer",
    )
    assert falls_short(_summary(145, 200, 12.9), product)[0] is False
    # apart, but faster where it succeeds: said beside the verdict
    short, how = falls_short(_summary(100, 200, 5.0), product)
    assert short and how.endswith("its median 2.00x shorter")
    # better than the product: not short, and said so
    assert falls_short(_summary(190, 200, 5.0), product) == (
        False,
        "it does better: its interval lies above; its median 2.00x shorter",
    )


def test_the_ablation_beside_is_reported_not_judged_and_the_oracle_within_its_interval():
    product = _summary(156, 200, 16.0)
    judged = _by_target(
        {
            "dipole": product,
            "torque_only": _summary(3, 200, 11.8),
            "oracle": _summary(150, 200, 15.0),  # 75.0%, its interval reaches 78%
        }
    )
    beside = judged["`torque_only` falls short of `dipole`"]
    assert beside.met is None and beside.word.startswith("reported beside")
    assert judged["`oracle` at least as good as `dipole` within its interval"].met is True
    worse = _by_target({"dipole": product, "oracle": _summary(120, 200, 15.0)})
    assert worse["`oracle` at least as good as `dipole` within its interval"].met is False


def test_the_markdown_names_the_setting_and_marks_misses():
    text = "\n".join(targets_markdown({"dipole": _summary(150, 200, 16.0)}, "speed=0.004"))
    assert text.startswith("### Targets at speed=0.004")
    assert "| `dipole` success >= 98% | 150/200 = 75.0% (68.6%-80.5%) | **missed** (by 23.0" in text
