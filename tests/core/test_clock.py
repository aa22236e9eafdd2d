"""The clocks a run's devices share: times from the run's start, and the paced simulation
that waits for a late tick instead of making its robot late (core/clock.py)."""

import time

import pytest

from core.clock import MonotonicClock, PacedClock


def test_a_runs_monotonic_clock_starts_at_zero_not_at_the_machines_uptime():
    clock = MonotonicClock.from_now()
    assert 0.0 <= clock.now() < 1.0 < time.monotonic()
    assert MonotonicClock().now() == pytest.approx(time.monotonic(), abs=0.1)
    with pytest.raises(ValueError, match="origin_s"):
        MonotonicClock(float("nan"))


class Wall:
    """A wall clock the test moves: ``work`` is time a tick's work takes."""

    def __init__(self) -> None:
        self.t = 100.0
        self.waits: list[float] = []

    def __call__(self) -> float:
        return self.t

    def wait(self, seconds: float) -> None:
        self.waits.append(seconds)
        self.t += seconds

    def work(self, seconds: float) -> None:
        self.t += seconds


def test_the_paced_clock_waits_for_the_wall_and_work_takes_no_simulated_time():
    wall = Wall()
    clock = PacedClock(wall, wall.wait)
    assert clock.now() == 0.0
    wall.work(0.004)  # a tick's work
    assert clock.now() == 0.0  # no simulated time passed: the tick cannot be late
    clock.sleep(0.010)
    assert clock.now() == pytest.approx(0.010) and wall.waits == [pytest.approx(0.006)]
    assert clock.slipped_s == 0.0


def test_on_a_busy_machine_the_paced_clock_slows_down_and_does_not_race_to_catch_up():
    wall = Wall()
    clock = PacedClock(wall, wall.wait)
    wall.work(0.030)  # a little late: caught up over the next ticks
    clock.sleep(0.010)
    assert wall.waits == [] and clock.slipped_s == 0.0
    wall.work(0.500)  # a stall: the simulation lets it go
    clock.sleep(0.010)
    assert clock.slipped_s == pytest.approx(0.510)
    clock.sleep(0.010)  # paced again from there, not a burst of ticks
    assert wall.waits == [pytest.approx(0.010)]
    assert clock.now() == pytest.approx(0.030)
