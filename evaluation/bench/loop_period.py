"""Benchmark: period accuracy of the control loop in real time.

Runs ``controller.loop.ControlLoop`` on ``MonotonicClock`` at ``--rate-hz`` for
``--duration-s`` with the sim twins (arm, gripper, GelSight Mini camera rendering frames at
25 fps, gamepad) on the same clock, the real tactile estimator (the Mini's own
configuration) and a trivial machine that commands a zero twist, i.e. the loop's full tick
without a decision worth timing. Prints, in ms: the tick-start lateness (start minus its
deadline: the period error of a deadline-paced loop), the deviation of each period from the
nominal one, the work per tick, then the overruns and the machine. Target (issue 13): p99
period error <= 1 ms at 100 Hz.

Run: ``.venv/bin/python scripts/bench_loop.py [--duration-s 20] [--rate-hz 100]
[--rt-priority 50]`` (SCHED_FIFO, ``loop.rt_priority``; needs CAP_SYS_NICE).
"""

from __future__ import annotations

import argparse

import numpy as np

from controller.insertion.interface import Command, Observation, Phase, Transition
from controller.loop import ControlLoop, LoopConfig, TickRecord
from controller.tactile import estimator_for_sensor
from core.clock import MonotonicClock
from core.config import CONFIG_ROOT
from core.devices import Devices, Twist
from drivers import registry
from evaluation.common.cli_support import integer, number, run_tool
from evaluation.common.machine_info import describe_machine


class HoldStill:
    """The trivial machine: a zero twist every tick, never done."""

    phase = Phase.APPROACH
    transitions: tuple[Transition, ...] = ()

    def step(self, observation: Observation) -> Command:
        return Command(twist=Twist())


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--duration-s", type=number(0.1, 3600.0, "s"), default=20.0, help="run length, s"
    )
    parser.add_argument("--rate-hz", type=number(1.0, 1000.0, "Hz"), default=100.0,
                        help="loop rate, Hz")  # fmt: skip
    parser.add_argument(
        "--rt-priority",
        type=integer(1, 99),
        default=None,
        help="SCHED_FIFO priority of the loop (loop.rt_priority); default: none",
    )
    args = parser.parse_args(argv)
    return run_tool("bench_loop", lambda: bench(args.duration_s, args.rate_hz, args.rt_priority))


def bench(duration_s: float, rate_hz: float, rt_priority: int | None) -> int:
    clock = MonotonicClock()

    def load(path: str):
        return registry.load_device(CONFIG_ROOT / path, backend="sim", clock=clock)

    devices = Devices(
        arm=load("robot/xarm6.yaml"),
        gripper=load("gripper/hande.yaml"),
        tactile=load("sensors/gelsight_mini_camera.yaml"),
        gamepad=load("gamepad/xbox.yaml"),
    )
    records: list[TickRecord] = []
    with devices.arm, devices.gripper, devices.tactile, devices.gamepad:
        loop = ControlLoop(
            HoldStill(),
            devices,
            estimator_for_sensor("gelsight_mini"),
            clock,
            LoopConfig(rate_hz=rate_hz, max_consecutive_overruns=100_000,
                       max_overruns_in_window=100_000, overrun_window_ticks=100_000,
                       rt_priority=rt_priority),
            observer=records.append,
        )  # fmt: skip
        result = loop.run(max_duration_s=duration_s)
    period_s = 1.0 / rate_hz
    starts = np.array([r.timing.start_s for r in records])
    lateness_ms = (starts - np.array([r.timing.deadline_s for r in records])) * 1e3
    deviation_ms = np.abs(np.diff(starts) - period_s) * 1e3
    work_ms = np.array([r.timing.end_s - r.timing.start_s for r in records]) * 1e3
    policy = "default scheduler" if rt_priority is None else f"SCHED_FIFO {rt_priority}"
    print(
        f"control loop, {rate_hz:g} Hz, {duration_s:g} s real time, sim twins + estimator, "
        f"{policy}\n"
    )
    print("| ms | p50 | p99 | max |")
    print("|---|---:|---:|---:|")
    for name, values in (
        ("tick-start lateness (period error)", lateness_ms),
        ("|period - nominal|", deviation_ms),
        ("work per tick", work_ms),
    ):
        p50, p99 = np.percentile(values, [50, 99])
        print(f"| {name} | {p50:.3f} | {p99:.3f} | {values.max():.3f} |")
    stats = result.stats
    print(f"\nticks {stats.ticks}, overruns {stats.overruns}, skipped deadlines {stats.skipped}, "
          f"ended: {result.reason}")  # fmt: skip
    print(f"\nMachine: {describe_machine('one process, shared machine (other jobs running)')}")
    return 0
