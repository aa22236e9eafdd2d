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
    assert judged["`dipole` 0 insertion-force violations"].met is False
    # controllers not in the grid are not judged, and say so
    for absent in (
        "`dipole` at least as successful as `blind`",
        "`oracle` at least as successful as `dipole`",
    ):
        assert judged[absent].met is None and judged[absent].word == "not run"

    met = _by_target({"dipole": _summary(198, 200, 14.0)})
    assert met["`dipole` success >= 98%"].met and met["`dipole` 0 insertion-force violations"].met


def test_against_blind_the_product_must_succeed_as_often_and_be_no_slower_over_every_trial():
    product = _summary(190, 200, 7.0)
    judged = _by_target({"dipole": product, "blind": _summary(180, 200, 6.5)})
    as_often = judged["`dipole` at least as successful as `blind`"]
    assert as_often.met is True and as_often.note == "+10 trials"
    median = judged["`dipole` median time to insert <= `blind`'s (every trial)"]
    assert median.met is False and median.note == "by 0.50 s"
    # blind's 20 failures put its p90 on a failure: never, which any finite p90 beats
    p90 = judged["`dipole` p90 time to insert <= `blind`'s (every trial)"]
    assert p90.met is True and p90.measured == "`dipole` 7.00 s, `blind` never"
    # the product's own p90 on a failure misses, whatever the baseline's
    worse = _by_target({"dipole": _summary(170, 200, 5.0), "blind": _summary(170, 200, 9.0)})
    assert worse["`dipole` p90 time to insert <= `blind`'s (every trial)"].met is False
    assert worse["`dipole` median time to insert <= `blind`'s (every trial)"].met is True
    assert worse["`dipole` at least as successful as `blind`"].note == "as many"


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


def test_the_ablations_are_judged_by_their_intervals_and_the_oracle_by_its_successes():
    product = _summary(156, 200, 16.0)
    judged = _by_target(
        {
            "dipole": product,
            "zero_torque": _summary(140, 200, 30.0),  # twice as slow, intervals overlapping
            "torque_only": _summary(3, 200, 11.8),
            "oracle": _summary(156, 200, 15.0),
        }
    )
    ablation = judged["`zero_torque` falls short of `dipole`, the intervals apart"]
    assert ablation.met is False and "the intervals overlap" in ablation.note
    beside = judged["`torque_only` falls short of `dipole`"]
    assert beside.met is None and beside.word.startswith("reported beside")
    assert judged["`oracle` at least as successful as `dipole`"].met is True
    worse = _by_target({"dipole": product, "oracle": _summary(150, 200, 15.0)})
    oracle = worse["`oracle` at least as successful as `dipole`"]
    assert oracle.met is False and oracle.note == "-6 trials"
    apart = _by_target({"dipole": product, "zero_torque": _summary(100, 200, 16.0)})
    assert apart["`zero_torque` falls short of `dipole`, the intervals apart"].met is True


def test_the_markdown_names_the_setting_and_marks_misses():
    text = "\n".join(targets_markdown({"dipole": _summary(150, 200, 16.0)}, "speed=0.004"))
    assert text.startswith("### Targets at speed=0.004")
    assert "| `dipole` success >= 98% | 150/200 = 75.0% (68.6%-80.5%) | **missed** (by 23.0" in text
