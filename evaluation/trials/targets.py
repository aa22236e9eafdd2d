"""The product's insertion targets, judged from a comparison's batch summaries.

Each target names what it asks, what the trials measured, and a verdict (``met``,
``missed`` with by how much, or ``not run`` when a controller it needs is not in the grid).
"Falls short" is the issue's rule: the two 95% Wilson intervals do not overlap (the lower
one's top under the other's bottom), or the median time to insert is at least
``SLOWER_FACTOR`` times longer. A summary is ``evaluation/trials/summary.summarize``'s dict;
rates are fractions, times simulated seconds, forces N.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

PRODUCT = "dipole"
SUCCESS_TARGET = 0.98  # dipole's success rate per task
MEDIAN_TIME_TARGET_S = 15.0  # dipole's median time to insert
SLOWER_FACTOR = 1.3  # "a median time to insert at least 30% longer"
# what must fall short of the product (its machine without the torques, on FingerVision's
# torques, and the same spiral without touch), and what is reported beside it (its machine
# without the forces); ``align``, the machine it replaced, is compared when run, not judged
MUST_FALL_SHORT = ("zero_torque", "fingervision", "blind")
REPORTED_BESIDE = ("torque_only",)
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


def falls_short(other: Summary, product: Summary) -> tuple[bool, str]:
    """Whether ``other`` falls short of ``product`` by the issue's rule, and how the two
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


def verdicts(summaries: Mapping[str, Summary]) -> list[Verdict]:
    """The targets for one task at one setting; ``summaries``: controller -> summary."""
    product = summaries.get(PRODUCT)
    if product is None or not product["n"]:
        return [Verdict(f"`{PRODUCT}` success >= {SUCCESS_TARGET:.0%}", "", None)]
    rate = product["success_rate"]
    median = product["median_time_s"]
    violations = product["insertion_force_violation_trials"]
    result = [
        Verdict(
            f"`{PRODUCT}` success >= {SUCCESS_TARGET:.0%}",
            _rate(product),
            rate >= SUCCESS_TARGET,
            "" if rate >= SUCCESS_TARGET else f"by {100 * (SUCCESS_TARGET - rate):.1f} points",
        ),
        Verdict(
            f"`{PRODUCT}` median time to insert <= {MEDIAN_TIME_TARGET_S:g} s",
            _median(product),
            median is not None and median <= MEDIAN_TIME_TARGET_S,
            ""
            if median is None or median <= MEDIAN_TIME_TARGET_S
            else f"by {median - MEDIAN_TIME_TARGET_S:.2f} s",
        ),
        Verdict(
            f"`{PRODUCT}` 0 insertion-force violations",
            f"{violations} trials over the limit",
            violations == 0,
            "" if violations == 0 else f"{violations} trials",
        ),
    ]
    for name in (*MUST_FALL_SHORT, *REPORTED_BESIDE):
        other = summaries.get(name)
        asks = f"`{name}` falls short of `{PRODUCT}`"
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
            result.append(Verdict(asks, measured, short, how))
    oracle = summaries.get(REFERENCE)
    asks = f"`{REFERENCE}` at least as good as `{PRODUCT}` within its interval"
    if oracle is None or not oracle["n"]:
        result.append(Verdict(asks, "", None))
    else:
        ci = oracle["success_ci95"]
        result.append(Verdict(asks, f"{_rate(oracle)}, {_median(oracle)}", ci[1] >= rate))
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
