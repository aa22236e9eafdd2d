"""The product's insertion targets, judged from a comparison's batch summaries.

Each target names what it asks, what the trials measured, and a verdict (``met``,
``missed`` with by how much, or ``not run`` when a controller it needs is not in the grid).
Against the force-threshold spiral (``blind``) the product must be at least as successful
and no slower, by its median and its p90 over every trial with a failure counted as never
(``median_time_all_s``, ``p90_time_all_s``: the same seeds, so a controller cannot look fast
by failing its slow trials). Its ablation without the torques must fall short with the two
95% Wilson intervals apart (the lower one's top under the other's bottom); ``fingervision``
and ``torque_only`` are reported beside, by that rule or a median ``SLOWER_FACTOR`` times
longer. The oracle (the true wrench) should succeed at least as often. A summary is
``evaluation/trials/summary.summarize``'s dict; rates are fractions, times simulated
seconds, forces N.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

PRODUCT = "dipole"
SUCCESS_TARGET = 0.98  # dipole's success rate per task
BASELINE = "blind"  # the force-threshold spiral: as successful, and no slower
SLOWER_FACTOR = 1.3  # "a median time to insert at least 30% longer"
INTERVALS_APART = ("zero_torque",)  # the product's machine with its torques zeroed
REPORTED_BESIDE = ("fingervision", "torque_only")
REFERENCE = "oracle"

Summary = Mapping[str, Any]


@dataclass(frozen=True)
class Verdict:
    """One target: what it asks, what was measured, and ``met`` (None: not judged)."""

    target: str
    measured: str
    met: bool | None
    note: str = ""

    @property
    def word(self) -> str:
        if self.met is None:
            return self.note or "not run"
        word = "met" if self.met else "**missed**"
        return f"{word} ({self.note})" if self.note else word


def _rate(summary: Summary) -> str:
    ci = summary["success_ci95"]
    interval = "" if ci is None else f" ({ci[0]:.1%}-{ci[1]:.1%})"
    return f"{summary['successes']}/{summary['n']} = {summary['success_rate']:.1%}{interval}"


def _median(summary: Summary) -> str:
    median = summary["median_time_s"]
    return "no success" if median is None else f"median {median:.2f} s"


def _seconds(value: float | None) -> str:
    return "never" if value is None else f"{value:.2f} s"


def falls_short(other: Summary, product: Summary) -> tuple[bool, str]:
    """Whether ``other`` falls short of ``product`` (its interval below, or its median
    ``SLOWER_FACTOR`` times longer), and how the two
    compare (the intervals, then the medians: a shorter one is said even when it falls
    short)."""
    ci_other, ci_product = other["success_ci95"], product["success_ci95"]
    m_other, m_product = other["median_time_s"], product["median_time_s"]
    below = ci_other is not None and ci_product is not None and ci_other[1] < ci_product[0]
    above = ci_other is not None and ci_product is not None and ci_other[0] > ci_product[1]
    if below:
        rates = "the intervals do not overlap"
    elif above:
        rates = "it does better: its interval lies above"
    else:
        rates = "the intervals overlap"
    if m_other is None or m_product is None:
        return below, rates
    ratio = m_other / m_product
    slower = ratio >= SLOWER_FACTOR
    if slower:
        medians = f"its median {ratio:.2f}x longer"
    elif m_product >= SLOWER_FACTOR * m_other:
        medians = f"its median {1 / ratio:.2f}x shorter"
    else:
        medians = "the medians within 30%"
    return below or slower, f"{rates}; {medians}"


def _no_slower(product: Summary, baseline: Summary, key: str, what: str) -> Verdict:
    """The product's ``key`` time (over every trial) no longer than the baseline's."""
    mine, theirs = product[key], baseline[key]
    measured = f"`{PRODUCT}` {_seconds(mine)}, `{BASELINE}` {_seconds(theirs)}"
    asks = f"`{PRODUCT}` {what} time to insert <= `{BASELINE}`'s (every trial)"
    if mine is None:
        return Verdict(asks, measured, False, "it reaches a failure")
    if theirs is None or mine <= theirs:
        return Verdict(asks, measured, True)
    return Verdict(asks, measured, False, f"by {mine - theirs:.2f} s")


def _against_baseline(product: Summary, baseline: Summary | None) -> list[Verdict]:
    asks = f"`{PRODUCT}` at least as successful as `{BASELINE}`"
    if baseline is None or not baseline["n"]:
        return [Verdict(asks, "", None)]
    more = product["successes"] - baseline["successes"]
    return [
        Verdict(
            asks,
            f"{_rate(baseline)}",
            more >= 0,
            f"{more:+d} trials" if more else "as many",
        ),
        _no_slower(product, baseline, "median_time_all_s", "median"),
        _no_slower(product, baseline, "p90_time_all_s", "p90"),
    ]


def verdicts(summaries: Mapping[str, Summary]) -> list[Verdict]:
    """The targets for one task at one setting; ``summaries``: controller -> summary."""
    product = summaries.get(PRODUCT)
    if product is None or not product["n"]:
        return [Verdict(f"`{PRODUCT}` success >= {SUCCESS_TARGET:.0%}", "", None)]
    rate = product["success_rate"]
    violations = product["insertion_force_violation_trials"]
    result = [
        Verdict(
            f"`{PRODUCT}` success >= {SUCCESS_TARGET:.0%}",
            _rate(product),
            rate >= SUCCESS_TARGET,
            "" if rate >= SUCCESS_TARGET else f"by {100 * (SUCCESS_TARGET - rate):.1f} points",
        ),
        Verdict(
            f"`{PRODUCT}` 0 insertion-force violations",
            f"{violations} trials over the limit",
            violations == 0,
            "" if violations == 0 else f"{violations} trials",
        ),
        *_against_baseline(product, summaries.get(BASELINE)),
    ]
    for name in (*INTERVALS_APART, *REPORTED_BESIDE):
        other = summaries.get(name)
        asks = f"`{name}` falls short of `{PRODUCT}`"
        if name in INTERVALS_APART:
            asks += ", the intervals apart"
        if other is None or not other["n"]:
            result.append(Verdict(asks, "", None))
            continue
        short, how = falls_short(other, product)
        measured = f"{_rate(other)}, {_median(other)}"
        if name in REPORTED_BESIDE:
            result.append(
                Verdict(
                    asks,
                    measured,
                    None,
                    f"reported beside; {'short' if short else 'not short'}: {how}",
                )
            )
        else:
            apart = how.startswith("the intervals do not overlap")
            result.append(Verdict(asks, measured, apart, how))
    oracle = summaries.get(REFERENCE)
    asks = f"`{REFERENCE}` at least as successful as `{PRODUCT}`"
    if oracle is None or not oracle["n"]:
        result.append(Verdict(asks, "", None))
    else:
        more = oracle["successes"] - product["successes"]
        result.append(
            Verdict(
                asks,
                f"{_rate(oracle)}, {_median(oracle)}",
                more >= 0,
                f"{more:+d} trials" if more else "as many",
            )
        )
    return result


def targets_markdown(summaries: Mapping[str, Summary], setting: str) -> list[str]:
    """The targets as markdown lines: a heading naming the ``setting``, then a table."""
    lines = [
        f"### Targets at {setting}",
        "",
        "| target | measured | verdict |",
        "|---|---|---|",
    ]
    for verdict in verdicts(summaries):
        lines.append(f"| {verdict.target} | {verdict.measured or '–'} | {verdict.word} |")
    return lines
