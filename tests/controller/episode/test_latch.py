"""The latched topics' rule: written first, on each change, and again after a quiet period."""

from __future__ import annotations

from controller.episode.recorder import Latch


def test_a_latch_is_due_first_on_each_change_and_after_its_period():
    latch = Latch(period_s=1.0)
    due = [latch.due(key, t) for key, t in [("a", 0.0), ("a", 0.5), ("b", 0.6), ("b", 1.59),
                                            ("b", 1.6), ("b", 2.0), ("a", 2.01)]]  # fmt: skip
    assert due == [True, False, True, False, True, False, True]
