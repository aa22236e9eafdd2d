"""The insertion scene's profile by part (evaluation/bench/scene_profile.py)."""

from __future__ import annotations

import time

import pytest

from evaluation.bench.scene_profile import (
    OTHER,
    part_clock,
    part_of_file,
    part_times,
    profile_call,
    top_functions,
)


def test_files_map_to_their_parts_and_libraries_to_none():
    assert part_of_file("/x/controller/tactile/grid_lk.py") == "estimator"
    assert part_of_file("/x/drivers/sim/twins/tcp_motion.py") == "arm twin"
    assert part_of_file("/x/drivers/sim/render/gel_renderer.py") == "rendering"
    assert part_of_file("/x/drivers/sim/scenes/insertion/coupling.py") == "gel solve"
    assert part_of_file("/x/drivers/sim/scenes/insertion/world.py") == "loop"
    assert part_of_file("/x/site-packages/numpy/linalg/_linalg.py") is None
    assert part_of_file("~") is None


class _Stats:
    """What ``part_times`` reads of a ``pstats.Stats``: ``stats``, function -> (primitive
    calls, calls, own s, cumulative s, callers -> (the same four, for that caller))."""

    def __init__(self, table):
        self.stats = table


ESTIMATE = ("/r/controller/tactile/estimator.py", 1, "push")
STEP = ("/r/drivers/sim/scenes/insertion/physics.py", 2, "step_to")
NUMPY = ("/v/site-packages/numpy/_core/_methods.py", 3, "_sum")
REMAP = ("~", 0, "<remap>")
ORPHAN = ("~", 0, "<exec>")


def test_library_time_goes_to_the_callers_in_proportion():
    stats = _Stats(
        {
            ESTIMATE: (1, 1, 0.2, 1.0, {}),
            STEP: (1, 1, 0.1, 0.4, {}),
            # numpy's Python: 0.3 s for the estimator, 0.1 s for the physics
            NUMPY: (4, 4, 0.4, 0.6, {ESTIMATE: (3, 3, 0.3, 0.4), STEP: (1, 1, 0.1, 0.2)}),
            # a built-in called by numpy's Python only: split as numpy's own time is
            REMAP: (2, 2, 0.2, 0.2, {NUMPY: (2, 2, 0.2, 0.2)}),
            ORPHAN: (1, 1, 0.05, 0.05, {}),
        }
    )
    seconds = {p.part: p.seconds for p in part_times(stats)}
    assert seconds["estimator"] == pytest.approx(0.2 + 0.3 + 0.15)
    assert seconds["physics"] == pytest.approx(0.1 + 0.1 + 0.05)
    assert seconds[OTHER] == pytest.approx(0.05)
    assert sum(p.share for p in part_times(stats)) == pytest.approx(1.0)


def _busy(seconds: float) -> None:
    end = time.process_time() + seconds
    while time.process_time() < end:
        pass


class _Outer:
    def run(self) -> None:
        _busy(0.03)
        _Inner().run()


class _Inner:
    def run(self) -> None:
        _busy(0.05)


def test_the_part_clock_counts_each_part_without_the_parts_it_calls():
    original = _Outer.__dict__["run"]
    entry_points = ((_Outer, "run", "outer"), (_Inner, "run", "inner"))
    with part_clock(entry_points) as seconds:
        _Outer().run()
    assert seconds["outer"] == pytest.approx(0.03, abs=0.01)
    assert seconds["inner"] == pytest.approx(0.05, abs=0.01)
    assert _Outer.__dict__["run"] is original  # unpatched after the block


def test_a_profiled_call_lists_its_costliest_functions_by_part():
    stats = profile_call(lambda: _Outer().run())
    rows = {
        where.split("(")[-1]: (calls, part) for where, calls, _, part in top_functions(stats, 4)
    }
    assert rows["_busy)"] == (2, "library")  # this file is no part of the scene
    assert "<built-in method time.process_time>" in rows  # the busy loop's clock
