"""The control loop on sim twins: pacing, overruns, the watchdog's trips, the safe stop,
signals, and what it sends. Time is a ManualClock except in one short real-time run."""

from __future__ import annotations

import dataclasses
import math
import os
import signal
import threading

import numpy as np
import pytest

from controller.insertion.interface import Command, GripperTarget, InHandEstimate, Phase
from controller.loop import ControlLoop, LoopConfig, LoopStats
from controller.safety import LimitsConfig, Watchdog
from controller.tactile import estimator_for_sensor
from controller.tactile.wrench import WrenchEstimate
from core.clock import MonotonicClock
from core.devices import ArmState, Pose, Twist
from drivers.sim.twins.gamepad import PadEvent
from tests.controller.conftest import ScriptedEstimator, ScriptedMachine, sim_devices
from tests.script_runs import exit_code

PERIOD = 0.01


class StopSpy:
    """Wraps the arm, noting the clock time of every ``stop()``."""

    def __init__(self, arm, clock) -> None:
        self._arm, self._clock = arm, clock
        self.stops: list[float] = []

    def __getattr__(self, name):
        return getattr(self._arm, name)

    def stop(self) -> None:
        self.stops.append(self._clock.now())
        self._arm.stop()


def make_loop(machine, devices, clock, *, estimator=None, observer=None, arm=None, **config):
    if arm is not None:
        devices = dataclasses.replace(devices, arm=arm)
    return ControlLoop(
        machine,
        devices,
        estimator if estimator is not None else ScriptedEstimator(),
        clock,
        LoopConfig(**config),
        observer=observer,
    )


class EstimatingMachine(ScriptedMachine):
    """Makes an in-hand estimate at its 3rd and 5th steps (two at the 5th)."""

    def __init__(self) -> None:
        super().__init__(done_after=8)
        self.in_hand_estimates: tuple[InHandEstimate, ...] = ()

    def step(self, observation):
        if self.steps in (2, 4):
            made = InHandEstimate(observation.t_s, "thickness", 0.01, 2e-4, "rock", False)
            more = (dataclasses.replace(made, kept=True),) if self.steps == 4 else ()
            self.in_hand_estimates += (made, *more)
        return super().step(observation)


def test_each_tick_record_carries_the_in_hand_estimates_made_since_the_last(devices, clock):
    records = []
    machine = EstimatingMachine()
    make_loop(machine, devices, clock, observer=records.append).run()
    carried = [[e.kept for e in r.in_hand_estimates] for r in records]
    assert carried == [[], [], [False], [], [False, True], [], [], []]
    assert [e for r in records for e in r.in_hand_estimates] == list(machine.in_hand_estimates)
    # a machine without the attribute makes none
    records.clear()
    make_loop(ScriptedMachine(done_after=3), devices, clock, observer=records.append).run()
    assert [r.in_hand_estimates for r in records] == [(), (), ()]


def test_ticks_start_on_deadlines_k_periods_from_the_start(devices, clock):
    records = []
    loop = make_loop(ScriptedMachine(done_after=20), devices, clock, observer=records.append)
    t0 = clock.now()
    result = loop.run()
    assert result.reason == "done" and result.phase is Phase.DONE
    starts = [r.timing.start_s for r in records]
    assert starts == pytest.approx([t0 + k * PERIOD for k in range(20)], abs=1e-9)
    assert [r.timing.index for r in records] == list(range(20))
    assert result.stats.ticks == 20 and result.stats.overruns == 0
    assert result.stats.period_p50_s == pytest.approx(PERIOD)
    assert result.stats.lateness_max_s == pytest.approx(0.0, abs=1e-9)


def test_a_slow_step_is_an_overrun_and_the_missed_deadlines_are_skipped(devices, clock):
    def script(obs, k):
        if k in (3, 7):
            clock.advance(0.025)  # 2.5 periods of work
        return Command()

    records = []
    loop = make_loop(
        ScriptedMachine(script, done_after=12), devices, clock, observer=records.append
    )
    t0 = clock.now()
    result = loop.run()
    assert result.stats.overruns == 2 and result.stats.skipped == 4
    indices = [r.timing.index for r in records]
    assert indices == [0, 1, 2, 3, 6, 7, 8, 9, 12, 13, 14, 15]
    assert [r.timing.overran for r in records].count(True) == 2
    for r in records:  # still on the grid
        assert r.timing.start_s == pytest.approx(t0 + r.timing.index * PERIOD, abs=1e-9)
    assert result.stats.period_max_s == pytest.approx(3 * PERIOD)
    assert result.stats.work_max_s == pytest.approx(0.025)


def test_repeated_overruns_trip_the_watchdog(devices, clock):
    def script(obs, k):
        clock.advance(0.012)
        return Command()

    machine = ScriptedMachine(script)
    loop = make_loop(machine, devices, clock, max_consecutive_overruns=3)
    result = loop.run()
    assert result.reason == "fault" and "3 in a row" in result.message
    assert machine.phase is Phase.FAILED and machine.observations[-1].fault == result.message
    assert result.stats.overruns == 3


def test_overruns_in_a_window_trip_the_watchdog(devices, clock):
    def script(obs, k):
        if k % 2 == 0:
            clock.advance(0.012)
        return Command()

    loop = make_loop(
        ScriptedMachine(script), devices, clock, max_consecutive_overruns=3,
        max_overruns_in_window=4, overrun_window_ticks=10,
    )  # fmt: skip
    result = loop.run()
    assert result.reason == "fault" and "4 in the last" in result.message


def test_stats_percentiles():
    starts = [0.0, 0.010, 0.021, 0.030, 0.040]
    deadlines = [0.0, 0.010, 0.020, 0.030, 0.040]
    ends = [0.002, 0.012, 0.023, 0.031, 0.045]
    stats = LoopStats.of(starts, deadlines, ends, overruns=0, skipped=0)
    assert stats.ticks == 5
    assert stats.period_max_s == pytest.approx(0.011)
    assert stats.period_p50_s == pytest.approx(np.percentile([0.01, 0.011, 0.009, 0.01], 50))
    assert stats.lateness_max_s == pytest.approx(0.001)
    assert stats.work_max_s == pytest.approx(0.005)
    assert stats.first_tick_s == starts[0]
    assert math.isnan(LoopStats.of([], [], [], 0, 0).period_p99_s)
    assert math.isnan(LoopStats.of([], [], [], 0, 0).first_tick_s)


def test_a_frozen_tactile_stream_trips_the_watchdog_and_stops_the_arm(devices, clock):
    spy = StopSpy(devices.arm, clock)
    stalled = []

    def observer(record):
        if record.timing.index == 20:
            devices.tactile.stall()
            stalled.append(clock.now())

    machine = ScriptedMachine(lambda obs, k: Command(twist=Twist((0.02, 0.0, 0.0))))
    estimator = ScriptedEstimator()
    loop = make_loop(machine, devices, clock, estimator=estimator, observer=observer, arm=spy,
                     tactile_max_age_s=0.1)  # fmt: skip
    result = loop.run()
    assert result.reason == "fault" and result.message.startswith("stale tactile frame")
    assert machine.phase is Phase.FAILED
    # The newest frame before the stall was at most one frame (40 ms) old; it turns stale
    # 0.1 s after it was captured, and the stop follows in that tick.
    assert spy.stops and spy.stops[0] - estimator.pushed[-1] <= 0.1 + PERIOD + 1e-9
    assert spy.stops[0] - stalled[0] <= 0.1 + PERIOD + 1e-9
    clock.advance(0.5)
    assert devices.arm.read_status().state is not ArmState.MOVING


def test_a_driver_fault_mid_run_stops_within_one_period(devices, clock):
    spy = StopSpy(devices.arm, clock)
    injected = []

    def observer(record):
        if record.timing.index == 30:
            devices.arm.inject_fault(21, "simulated joint overcurrent")
            injected.append(clock.now())

    machine = ScriptedMachine(lambda obs, k: Command(twist=Twist((0.02, 0.0, 0.0))))
    result = make_loop(machine, devices, clock, observer=observer, arm=spy).run()
    assert result.reason == "fault" and "error code 21" in result.message
    assert len(spy.stops) == 1 and 0 < spy.stops[0] - injected[0] <= PERIOD + 1e-9
    assert machine.phase is Phase.FAILED
    assert machine.transitions[-1].reason == "device_fault"


def test_a_silent_gripper_is_a_driver_fault(devices, clock):
    def observer(record):
        if record.timing.index == 5:
            devices.gripper.set_responding(False)

    result = make_loop(ScriptedMachine(), devices, clock, observer=observer).run()
    assert result.reason == "fault" and result.message.startswith("device fault (gripper)")


def test_a_refused_command_is_a_driver_fault(devices, clock):
    devices.arm.emergency_stop()  # latched: motion commands raise, status shows no code
    machine = ScriptedMachine(lambda obs, k: Command(twist=Twist((0.01, 0.0, 0.0))))
    result = make_loop(machine, devices, clock).run()
    assert result.reason == "fault" and "device fault (arm)" in result.message
    assert "fault latched" in result.message


def takeover_machine(obs, k):
    return Command(twist=obs.teleop.twist) if obs.teleop.in_control else Command()


def test_a_lost_gamepad_in_control_trips_the_watchdog(devices, clock):
    devices.gamepad.play(
        [
            PadEvent(0.05, axes={"vx": 0.5}, buttons={"deadman": True}),
            PadEvent(0.20, attached=False),
        ]
    )
    records = []
    machine = ScriptedMachine(takeover_machine)
    result = make_loop(machine, devices, clock, observer=records.append).run()
    assert result.reason == "fault" and "gamepad lost" in result.message
    assert any(r.observation.teleop.in_control for r in records)
    moving = [r.command.twist.linear_m_s[0] for r in records if r.command and r.command.twist]
    assert max(moving) > 0  # the operator drove the arm before the pad was lost


class ReadSpy:
    """Wraps the tactile sensor, noting the clock time of every ``read_latest``."""

    def __init__(self, sensor, clock) -> None:
        self._sensor, self._clock = sensor, clock
        self.reads: list[float] = []

    def __getattr__(self, name):
        return getattr(self._sensor, name)

    def read_latest(self, max_age_s):
        self.reads.append(self._clock.now())
        return self._sensor.read_latest(max_age_s)


def test_a_lost_gamepad_stops_the_arm_before_the_ticks_other_reads(devices, clock):
    devices.gamepad.play(
        [
            PadEvent(0.05, axes={"vx": 0.5}, buttons={"deadman": True}),
            PadEvent(0.20, attached=False),
        ]
    )
    tactile, arm = ReadSpy(devices.tactile, clock), StopSpy(devices.arm, clock)
    records = []
    result = make_loop(ScriptedMachine(takeover_machine),
                       dataclasses.replace(devices, tactile=tactile), clock,
                       observer=records.append, arm=arm).run()  # fmt: skip
    tripped = records[-1]
    assert result.reason == "fault" and tripped.fault is not None
    assert not tripped.observation.teleop.connected  # the record shows the pad as read
    assert arm.stops[0] == tripped.timing.start_s  # stopped in the tick that read the unplug
    assert tripped.timing.start_s not in tactile.reads  # ... before reading the camera
    assert tripped.timing.start_s - records[-2].timing.start_s == pytest.approx(0.01)


def test_a_lost_gamepad_not_in_control_does_not_trip(devices, clock):
    devices.gamepad.play([PadEvent(0.05, attached=False)])
    result = make_loop(ScriptedMachine(takeover_machine, done_after=50), devices, clock).run()
    assert result.reason == "done"


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGINT])
def test_a_signal_stops_safely_within_one_period_and_restores_handlers(devices, clock, signum):
    before = signal.getsignal(signum)
    spy = StopSpy(devices.arm, clock)
    sent = []

    def observer(record):
        if record.timing.index == 10:
            sent.append(clock.now())
            os.kill(os.getpid(), signum)

    machine = ScriptedMachine(lambda obs, k: Command(twist=Twist((0.02, 0.0, 0.0))))
    result = make_loop(machine, devices, clock, observer=observer, arm=spy).run()
    assert result.reason == "signal" and result.message == signal.Signals(signum).name
    assert result.stats.ticks == 11
    assert len(spy.stops) == 1 and spy.stops[0] - sent[0] <= PERIOD + 1e-9
    assert signal.getsignal(signum) is before


def test_an_ignored_sigint_stays_ignored(devices, clock):
    before = signal.signal(signal.SIGINT, signal.SIG_IGN)  # as in a batch's worker
    try:
        seen = []
        machine = ScriptedMachine(
            lambda obs, k: seen.append(signal.getsignal(signal.SIGINT)) or Command(twist=Twist())
        )
        make_loop(machine, devices, clock).run(max_duration_s=0.05)
        assert seen and all(handler is signal.SIG_IGN for handler in seen)
    finally:
        signal.signal(signal.SIGINT, before)


def test_outside_the_main_thread_no_handler_is_installed(devices, clock):
    seen = []
    machine = ScriptedMachine(done_after=3)
    loop = make_loop(machine, devices, clock,
                     observer=lambda r: seen.append(signal.getsignal(signal.SIGTERM)))  # fmt: skip
    before = signal.getsignal(signal.SIGTERM)
    thread = threading.Thread(target=loop.run)
    thread.start()
    thread.join()
    assert seen == [before] * 3 and machine.phase is Phase.DONE


def test_an_exception_in_a_tick_ends_as_a_device_fault(devices, clock):
    """A bug in the machine: safe stop, the machine records FAILED, the observer sees the
    fault, the run ends "fault" naming the exception, and the handlers are restored."""

    def script(obs, k):
        if k == 4:
            raise RuntimeError("bug in a handler")
        return Command(twist=Twist((0.02, 0.0, 0.0)))

    spy, seen, machine = StopSpy(devices.arm, clock), [], ScriptedMachine(script)
    before = signal.getsignal(signal.SIGTERM)
    result = make_loop(machine, devices, clock, arm=spy, observer=seen.append).run()
    assert result.reason == "fault"
    assert result.message == "the tick raised RuntimeError: bug in a handler"
    assert len(spy.stops) == 1 and signal.getsignal(signal.SIGTERM) is before
    assert machine.phase is Phase.FAILED and machine.transitions[-1].reason == "device_fault"
    assert seen[-1].fault == result.message and seen[-1].command is None


@pytest.mark.parametrize(
    "error", [ValueError("frame 10x10: expected 320x240"), ConnectionResetError(104, "reset")]
)
def test_an_estimator_or_link_error_is_a_fault_too(devices, clock, error):
    class Failing(ScriptedEstimator):
        def push(self, image, t_s):
            if len(self.pushed) == 3:
                raise error
            return super().push(image, t_s)

    machine = ScriptedMachine(lambda obs, k: Command(twist=Twist((0.02, 0.0, 0.0))))
    spy = StopSpy(devices.arm, clock)
    result = make_loop(machine, devices, clock, estimator=Failing(), arm=spy).run()
    assert result.reason == "fault" and type(error).__name__ in result.message
    assert len(spy.stops) == 1 and machine.phase is Phase.FAILED


def test_a_failure_while_recording_the_fault_still_ends_the_run(devices, clock):
    def observer(record):
        if record.fault is not None:
            raise OSError(28, "No space left on device", "ticks.jsonl")
        if len(seen) == 5:
            raise OSError(28, "No space left on device", "ticks.jsonl")
        seen.append(record)

    seen = []
    spy = StopSpy(devices.arm, clock)
    result = make_loop(ScriptedMachine(), devices, clock, arm=spy, observer=observer).run()
    assert result.reason == "fault" and "No space left on device" in result.message
    assert len(spy.stops) == 1


def test_safe_stop_errors_are_reported_not_raised(devices, clock):
    class Broken(StopSpy):
        def stop(self):
            raise OSError("link down")

    result = make_loop(
        ScriptedMachine(done_after=2), devices, clock, arm=Broken(devices.arm, clock)
    ).run()
    assert result.reason == "done" and isinstance(result.safe_stop_error, OSError)


def test_commands_reach_the_devices(devices, clock):
    target = GripperTarget(width_m=0.012, speed_m_s=0.05, force_n=20.0)
    start = devices.arm.read_status().tcp

    def script(obs, k):
        if k < 50:
            return Command(twist=Twist((0.02, 0.0, 0.0)), gripper=target)
        if k == 50:
            return Command(rezero_tactile=True)
        goal = Pose((start.xyz_m[0], 0.01, start.xyz_m[2]), start.rpy_rad)
        return Command(pose=goal, gripper=target)

    moves = []
    gripper_move = devices.gripper.move
    devices.gripper.move = lambda *a: (moves.append(a), gripper_move(*a))
    estimator = ScriptedEstimator()
    machine = ScriptedMachine(script, done_after=120)
    result = make_loop(machine, devices, clock, estimator=estimator, rezero_frames=7).run()
    assert result.reason == "done"
    after_twist = machine.observations[51].arm.tcp.xyz_m
    assert after_twist[0] > start.xyz_m[0] + 0.005  # the twist moved it along +x
    assert devices.arm.read_status().tcp.xyz_m[1] > 0.005  # the pose target along +y
    assert moves == [(0.012, 0.05, 20.0)]  # sent once: unchanged targets are not resent
    assert estimator.rezeroed == [7]
    # A new frame is pushed once: 25 fps frames over 1.2 s of 100 Hz ticks.
    assert len(estimator.pushed) == len(set(estimator.pushed)) == pytest.approx(30, abs=1)


def test_the_tactile_budget_limits_the_command_in_the_loop(devices, clock):
    def pressed(t_s):
        base = WrenchEstimate.zero(t_s, zeroing=False, calibrated=True)
        return dataclasses.replace(base, tau_x=0.03, contact=True, degenerate=False)

    records = []
    machine = ScriptedMachine(lambda obs, k: Command(twist=Twist((0.01, 0.0, -0.01))),
                              done_after=5)  # fmt: skip
    loop = ControlLoop(
        machine, devices, ScriptedEstimator(pressed), clock, LoopConfig(),
        LimitsConfig(max_tilt_torque=0.02), observer=records.append,
    )  # fmt: skip
    loop.run()
    assert all(r.command.twist == Twist() for r in records)
    assert all("budget:tilt_torque" in r.limited for r in records)


def test_max_duration_ends_the_run(devices, clock):
    t0 = clock.now()
    result = make_loop(ScriptedMachine(), devices, clock).run(max_duration_s=0.5)
    assert result.reason == "max_duration" and result.stats.ticks == 50
    assert clock.now() - t0 == pytest.approx(0.5)


def test_with_the_real_estimator(devices, clock):
    estimator = estimator_for_sensor("gelsight_mini")
    machine = ScriptedMachine(done_after=30)
    make_loop(machine, devices, clock, estimator=estimator).run()
    wrenches = [obs.wrench for obs in machine.observations]
    assert wrenches[0] is not None and wrenches[-1] is not None
    assert not wrenches[-1].contact


def test_real_time_mode_is_the_same_loop():
    clock = MonotonicClock()
    machine = ScriptedMachine(done_after=5)
    with sim_devices(clock, activate=False) as devices:
        result = ControlLoop(machine, devices, ScriptedEstimator(), clock).run()
    assert result.reason == "done" and result.stats.ticks == 5


def test_loop_config_checks_its_keys():
    with pytest.raises(ValueError, match="key 'hold_s': expected at least one period"):
        LoopConfig(rate_hz=100.0, hold_s=0.005)
    with pytest.raises(ValueError, match="key 'max_overruns_in_window'"):
        LoopConfig(max_overruns_in_window=20, overrun_window_ticks=10)
    with pytest.raises(ValueError, match="key 'rate_hz'"):
        LoopConfig(rate_hz=0.0)


def test_rt_priority_switches_to_sched_fifo_and_back(devices, clock, monkeypatch):
    calls = []
    monkeypatch.setattr(os, "sched_getscheduler", lambda pid: os.SCHED_OTHER)
    monkeypatch.setattr(os, "sched_getparam", lambda pid: os.sched_param(0))
    monkeypatch.setattr(os, "sched_setscheduler", lambda pid, *a: calls.append(a))
    make_loop(ScriptedMachine(done_after=2), devices, clock, rt_priority=40).run()
    assert calls == [(os.SCHED_FIFO, os.sched_param(40)), (os.SCHED_OTHER, os.sched_param(0))]


def test_a_refused_rt_priority_is_a_one_line_error_before_any_tick(devices, clock, monkeypatch):
    def refuse(pid, *args):
        raise PermissionError(1, "Operation not permitted")

    monkeypatch.setattr(os, "sched_setscheduler", refuse)
    machine = ScriptedMachine(done_after=2)
    with pytest.raises(PermissionError, match="key 'rt_priority': SCHED_FIFO priority 40 refused"):
        make_loop(machine, devices, clock, rt_priority=40).run()
    assert machine.steps == 0


def test_the_bench_script_runs(capsys):
    assert exit_code("bench_loop", ["--duration-s", "0.3"]) == 0
    out = capsys.readouterr().out
    assert "tick-start lateness" in out and "Machine:" in out
    assert exit_code("bench_loop", ["--rate-hz", "0"]) == 2
    assert "--rate-hz" in capsys.readouterr().err


def test_a_limit_holding_the_machine_back_trips_the_watchdog(devices, clock):
    """A target beyond the workspace box: the limiter holds the arm at the box's face, and
    after max_held_by_limits_s of that the run ends in a fault, not against the face."""
    records = []
    machine = ScriptedMachine(lambda obs, k: Command(twist=Twist((0.05, 0.0, 0.0))))
    result = make_loop(machine, devices, clock, observer=records.append,
                       max_held_by_limits_s=0.5).run(max_duration_s=30.0)  # fmt: skip
    assert result.reason == "fault" and "workspace limit held the commands back" in result.message
    held = [r for r in records if "workspace" in r.limited]
    assert held and 0.5 <= records[-1].timing.start_s - held[0].timing.start_s <= 0.5 + 2 * PERIOD
    assert machine.phase is Phase.FAILED


def test_an_operator_held_at_the_box_face_is_not_tripped(devices, clock):
    watchdog = Watchdog(0.15, 5, 20, 100, max_held_by_limits_s=0.5)
    for k in range(200):
        assert watchdog.record_limits(k * PERIOD, ("workspace",), operator_in_control=True) is None
    for k in range(49):  # the machine held 0.48 s, then free again: no trip
        assert watchdog.record_limits(k * PERIOD, ("tilt", "speed"), False) is None
    assert watchdog.record_limits(0.5, ("speed",), False) is None
    assert watchdog.record_limits(0.6, ("workspace",), False) is None
    assert watchdog.record_limits(1.1, ("workspace",), False).startswith("the workspace limit")
