"""Benchmark: period accuracy of the control loop in real time.

Runs ``controller.loop.ControlLoop`` on ``MonotonicClock`` at ``--rate-hz`` for
``--duration-s`` with the sim twins (arm, gripper, GelSight Mini camera rendering frames at
25 fps, gamepad) on the same clock, the real tactile estimator (the Mini's own
configuration) and a trivial machine that commands a zero twist, i.e. the loop's full tick
without a decision worth timing. Prints, in ms: the tick-start lateness (start minus its
deadline: the period error of a deadline-paced loop), the deviation of each period from the
nominal one, the work per tick, then the overruns and the machine. Target: p99
period error <= 1 ms at 100 Hz.

``--episode`` records the run to an episode (a temporary file: the writer thread, the
tactile tap and the tick logger, as every trial); ``--view`` adds the teleop demo's live view
(its own process, fed by the episode writer, drawing each frame; headless with
``SDL_VIDEODRIVER=dummy``), so the loop's timing can be compared with and without them.

Run: ``.venv/bin/python -m evaluation bench_loop [--duration-s 20] [--rate-hz 100]
[--rt-priority 50] [--episode] [--view]`` (SCHED_FIFO, ``loop.rt_priority``; needs
CAP_SYS_NICE).
"""

from __future__ import annotations

import argparse
import tempfile
from collections.abc import Callable
from contextlib import ExitStack
from pathlib import Path

import numpy as np

from controller.cli.support import integer, number, run_tool
from controller.episode.session import EpisodeRecording
from controller.insertion.interface import Command, Observation, Phase, Transition
from controller.loop import ControlLoop, LoopConfig, LoopResult, TickRecord
from controller.tactile import WrenchSource, estimator_for_sensor
from controller.view.feed import ViewFeed
from controller.view.window import LiveView
from core.clock import MonotonicClock
from core.config import CONFIG_ROOT
from core.devices import Devices, Twist
from core.sensor_profile import sensor_profile
from drivers import registry
from evaluation.common.machine_info import describe_machine

MINI_MM_PER_PX = sensor_profile("gelsight_mini").mm_per_px


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
    parser.add_argument("--episode", action="store_true", help="record an episode")
    parser.add_argument("--view", action="store_true", help="the live view (implies --episode)")
    args = parser.parse_args(argv)
    return run_tool(
        "bench_loop",
        lambda: bench(
            args.duration_s, args.rate_hz, args.rt_priority, args.episode or args.view, args.view
        ),  # fmt: skip
    )


def bench(
    duration_s: float,
    rate_hz: float,
    rt_priority: int | None,
    episode: bool = False,
    view: bool = False,
) -> int:
    with tempfile.TemporaryDirectory() as folder, ExitStack() as stack:
        recording, live = None, None
        if view:
            live = LiveView(["bench_loop"], Path(folder))
            stack.callback(live.close)
        if episode:
            listeners = [] if live is None else [ViewFeed(live.offer, MINI_MM_PER_PX)]
            recording = EpisodeRecording(
                Path(folder) / "episode.mcap", {}, task="bench", task_file="", overrides=(),
                seed=0, controller="hold_still", backend="sim", listeners=listeners,
            )  # fmt: skip
            stack.callback(recording.close)
        if live is not None:
            live.start()
        result, records = _run(duration_s, rate_hz, rt_priority, recording)
        what = "episode + live view" if view else "episode" if episode else "no episode"
        if live is not None:
            what += f" (view: {live.offered} frames offered, {live.dropped} dropped)"
    _report(duration_s, rate_hz, rt_priority, result, records, what)
    return 0


def _run(
    duration_s: float,
    rate_hz: float,
    rt_priority: int | None,
    recording: EpisodeRecording | None,
) -> tuple[LoopResult, list[TickRecord]]:
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
    source: WrenchSource = estimator_for_sensor("gelsight_mini")
    observer: Callable[[TickRecord], None] = records.append
    if recording is not None:
        recording.start(clock)
        source = recording.tap(source, clock)
        logger = recording.observer()

        def observer(tick: TickRecord) -> None:
            records.append(tick)
            logger(tick)

    with devices.arm, devices.gripper, devices.tactile, devices.gamepad:
        loop = ControlLoop(
            HoldStill(),
            devices,
            source,
            clock,
            LoopConfig(rate_hz=rate_hz, max_consecutive_overruns=100_000,
                       max_overruns_in_window=100_000, overrun_window_ticks=100_000,
                       rt_priority=rt_priority),
            observer=observer,
        )  # fmt: skip
        result = loop.run(max_duration_s=duration_s)
    return result, records


def _report(
    duration_s: float,
    rate_hz: float,
    rt_priority: int | None,
    result: LoopResult,
    records: list[TickRecord],
    what: str,
) -> None:
    period_s = 1.0 / rate_hz
    starts = np.array([r.timing.start_s for r in records])
    lateness_ms = (starts - np.array([r.timing.deadline_s for r in records])) * 1e3
    deviation_ms = np.abs(np.diff(starts) - period_s) * 1e3
    work_ms = np.array([r.timing.end_s - r.timing.start_s for r in records]) * 1e3
    policy = "default scheduler" if rt_priority is None else f"SCHED_FIFO {rt_priority}"
    print(
        f"control loop, {rate_hz:g} Hz, {duration_s:g} s real time, sim twins + estimator, "
        f"{policy}, {what}\n"
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
