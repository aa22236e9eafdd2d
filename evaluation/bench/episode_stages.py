"""Where the episode writer's thread spends its CPU (docs/EPISODES.md "Cost"): a simulated
usb_c trial run as fast as possible for ``--seconds`` of loop time (the search made to fail so
it lasts), with each record's encoding, its write (the MCAP channel's ``log``) and each file
flush timed on the writer thread (``time.thread_time_ns``), by topic.

The frames' JPEG is the camera's (the simulated twin encodes each frame it renders once an
episode asks for it, on the loop's thread: ``compress_frames``), so it is not the writer's;
it is timed too (the encoder the episode gives the twin) and reported on its own line, so the
cost that moved is in view.

The flushes follow the log time (one every ``flush_interval_s`` of it, and one at each phase
change), so a run faster than real time makes about as many per second of loop time as a
real-time one; the last line gives the real-time estimate: the records' work per second of
loop time plus one flush's mean cost times the flushes a real-time second makes. The code
runs warm here (no sleeps between batches), which a real-time run's does not (docs/EPISODES.md
"Cost"); ``--realtime`` runs the trial at real time instead (the watchdog's overrun policy
relaxed as in evaluation/bench/episode.py), as a product run does. The timers add about a
microsecond per record.

``--replay`` asks what the pauses cost: the trial's records (as the writer took them) are
written again into a new file on this thread, a flush's worth of log time at a time
(encode, then each channel's ``log``, then the flush, each timed), three ways: back to back;
after a sleep of one flush interval before each batch (as the logger waits at real time);
and after spinning that long instead (the thread kept busy, so what is lost in the pause is
not the thread's own). The same work, so any difference is the pause's.

    python -m evaluation bench_episode_stages [--seconds 20] [--seed 1] [--realtime]
    python -m evaluation bench_episode_stages --replay [--interval 0.07] [--seconds 20] [--seed 1]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from collections import Counter
from pathlib import Path
from typing import Any

from controller.episode.session import EPISODE_FILE, EpisodeOptions
from controller.episode.writer import EpisodeWriter
from controller.run import load_task
from core.subcommands import job_prog
from drivers.sim.twins.tactile import SimTactileSensor
from evaluation.bench.episode import RELAXED_OVERRUNS
from evaluation.common.machine_info import describe_machine
from evaluation.trials.trial import run


def _seconds(low: float, high: float) -> Any:
    """An argparse type: a number of seconds in [``low``, ``high``]."""

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            value = float("nan")
        if not low <= value <= high:
            expected = f"expected seconds in [{low:g}, {high:g}]"
            raise argparse.ArgumentTypeError(f"{expected}, got {text!r}")
        return value

    return parse


class StageTimes:
    """Writer-thread CPU (ns) by stage and topic, filled by the patched writer."""

    def __init__(self) -> None:
        self.encode_ns: Counter[str] = Counter()
        self.add_ns: Counter[str] = Counter()
        self.count: Counter[str] = Counter()
        self.flush_ns = 0
        self.flushes = 0
        self.busy_s = 0.0
        self.flush_interval_s = 0.0
        self.camera_jpeg_ns = 0
        self.camera_jpegs = 0

    def patch(self) -> Any:
        """Patch ``EpisodeWriter`` (log, __init__, close); returns a function that undoes it."""
        original_log, original_init = EpisodeWriter.log, EpisodeWriter.__init__
        original_close = EpisodeWriter.close
        original_register, original_flush = EpisodeWriter._register, EpisodeWriter._flush
        clock = time.thread_time_ns
        stages = self

        def log(self, topic, t_s, encode, payload):  # type: ignore[no-untyped-def]
            def timed(item: Any) -> bytes:
                began = clock()
                data = encode(item)
                stages.encode_ns[topic.name] += clock() - began
                stages.count[topic.name] += 1
                return data

            original_log(self, topic, t_s, timed, payload)

        def init(self, *args, **kwargs):  # type: ignore[no-untyped-def]
            original_init(self, *args, **kwargs)
            stages.flush_interval_s = self.flush_interval_s

        def register(self, topic):  # type: ignore[no-untyped-def]
            log = _timed_log(original_register(self, topic), topic.name, stages)
            self._channels[topic.name] = log
            return log

        def flush(self):  # type: ignore[no-untyped-def]
            began = clock()
            original_flush(self)
            stages.flush_ns += clock() - began
            stages.flushes += 1

        def close(self, outcome=None):  # type: ignore[no-untyped-def]
            original_close(self, outcome)
            stages.busy_s = self.busy_s

        EpisodeWriter.log, EpisodeWriter.close = log, close  # type: ignore[method-assign]
        EpisodeWriter.__init__ = init  # type: ignore[method-assign]
        EpisodeWriter._register, EpisodeWriter._flush = register, flush  # type: ignore[method-assign]
        original_compress = SimTactileSensor.compress_frames

        def compress_frames(self, encode):  # type: ignore[no-untyped-def]
            def camera_jpeg(image):  # type: ignore[no-untyped-def]
                began = clock()
                data = encode(image)
                stages.camera_jpeg_ns += clock() - began
                stages.camera_jpegs += 1
                return data

            original_compress(self, None if encode is None else camera_jpeg)

        SimTactileSensor.compress_frames = compress_frames  # type: ignore[method-assign]

        def undo() -> None:
            EpisodeWriter.log, EpisodeWriter.close = original_log, original_close  # type: ignore[method-assign]
            EpisodeWriter.__init__ = original_init  # type: ignore[method-assign]
            EpisodeWriter._register, EpisodeWriter._flush = original_register, original_flush  # type: ignore[method-assign]
            SimTactileSensor.compress_frames = original_compress  # type: ignore[method-assign]

        return undo


def _timed_log(log: Any, name: str, stages: StageTimes) -> Any:
    """An MCAP channel's ``log(data, log_time_ns)`` that adds its writer-thread CPU to
    ``stages.add_ns[name]``."""

    def timed(data: bytes, log_time: int) -> None:
        began = time.thread_time_ns()
        log(data, log_time)
        stages.add_ns[name] += time.thread_time_ns() - began

    return timed


Record = tuple[Any, int, Any, Any]
"""A queued record as the writer thread takes it: (topic, log time ns, encoder, payload)."""


def keep_records(records: list[Record]) -> Any:
    """Patch ``EpisodeWriter._write`` to append each record it writes to ``records``; returns
    a function that undoes it."""
    original = EpisodeWriter._write

    def write(self, item):  # type: ignore[no-untyped-def]
        records.append(item)
        original(self, item)

    EpisodeWriter._write = write  # type: ignore[method-assign]

    def undo() -> None:
        EpisodeWriter._write = original  # type: ignore[method-assign]

    return undo


def replay(records: list[Record], interval_s: float, pause: str) -> tuple[float, float, int]:
    """Write ``records`` again into a new file on this thread, ``interval_s`` of log time at a
    time: each batch's records (``_write``: encode and ``log``), then a flush, after
    ``pause`` (``none``, ``sleep`` or ``spin``: ``interval_s`` of wall time slept or spun).
    Returns the thread's CPU time for the records and for the flushes (s), and the batches.
    The writer's own thread is stopped first, so the work is this thread's."""
    with tempfile.TemporaryDirectory(prefix="bench_episode_replay_") as work:
        writer = EpisodeWriter(Path(work) / EPISODE_FILE, {})
        writer._stopping = True  # its logger thread returns at once (nothing queued)
        writer._wake.set()
        writer._thread.join()
        step_ns = round(interval_s * 1e9)
        records_ns = flush_ns = batches = 0
        i, n = 0, len(records)
        while i < n:
            end_ns, j = records[i][1] + step_ns, i
            while j < n and records[j][1] < end_ns:
                j += 1
            if pause == "sleep":
                time.sleep(interval_s)
            elif pause == "spin":
                until = time.perf_counter() + interval_s
                while time.perf_counter() < until:
                    pass
            began = time.thread_time_ns()
            for item in records[i:j]:
                writer._write(item)
            wrote = time.thread_time_ns()
            writer._flush()
            records_ns += wrote - began
            flush_ns += time.thread_time_ns() - wrote
            batches, i = batches + 1, j
        writer._finish()
        writer._stream.close()
    return records_ns / 1e9, flush_ns / 1e9, batches


def report_replay(records: list[Record], loop_s: float, interval_s: float) -> None:
    """Print ``replay``'s three ways, twice each, as % of a core per s of loop time."""
    print(f"{len(records)} records replayed, {interval_s:g} s of log time a batch\n")
    print("| pause before each batch | records, % | flushes, % | total, % of a core |")
    print("|---|---:|---:|---:|")
    for pause in ("none", "sleep", "spin") * 2:
        records_s, flush_s, _ = replay(records, interval_s, pause)
        print(f"| {pause} | {records_s / loop_s * 100:.2f} | {flush_s / loop_s * 100:.2f} | "
              f"{(records_s + flush_s) / loop_s * 100:.2f} |")  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog=job_prog("bench_episode_stages"), description=__doc__.splitlines()[0]
    )
    parser.add_argument("--seconds", type=_seconds(1.0, 600.0), default=20.0, help="loop time, s")
    parser.add_argument("--seed", type=int, default=1)
    mode = parser.add_mutually_exclusive_group()
    mode.add_argument(
        "--realtime", action="store_true", help="at real time: cold code after each wake-up"
    )
    mode.add_argument(
        "--replay", action="store_true", help="the records written again, with and without pauses"
    )
    parser.add_argument(
        "--interval", type=_seconds(0.001, 10.0), default=EpisodeOptions().flush_interval_s,
        help="with --replay: the log time a batch spans, s (default: the writer's flush interval)",
    )  # fmt: skip
    args = parser.parse_args(argv)
    budget = f"{args.seconds:g}"
    task = load_task("usb_c", [f"machine.timeouts.search_s={budget}",
                               f"machine.timeouts.total_s={budget}",
                               "machine.search.uncertainty_xy_m=0.0003",
                               *(RELAXED_OVERRUNS if args.realtime else ())])  # fmt: skip
    stages, records = StageTimes(), list[Record]()
    undo = keep_records(records) if args.replay else stages.patch()
    try:
        with tempfile.TemporaryDirectory(prefix="bench_episode_stages_") as work:
            out = Path(work) / "trial"
            began = time.monotonic()
            outcome = run(task, "dipole", args.seed, out_dir=out, episode=EpisodeOptions(),
                          realtime=args.realtime)  # fmt: skip
            wall_s = time.monotonic() - began
            size = (out / EPISODE_FILE).stat().st_size
    finally:
        undo()
    loop_s = outcome.loop.stats.ticks / task.config.loop.rate_hz
    print(f"Machine: {describe_machine('the trial in one process, its writer thread')}")
    if args.replay:
        print(f"usb_c seed {args.seed}: {loop_s:.1f} s of loop time")
        report_replay(records, loop_s, args.interval)
        return 0
    print(f"usb_c seed {args.seed}: {loop_s:.1f} s of loop time in {wall_s:.1f} s of wall "
          f"time, {sum(stages.count.values())} records, file {size / 1e6:.2f} MB\n")  # fmt: skip
    print(
        "| topic | records | encode, us each | write (log), us each | CPU per s of loop time, ms |"
    )
    print("|---|---|---|---|---|")
    for name in sorted(stages.count, key=lambda k: -(stages.encode_ns[k] + stages.add_ns[k])):
        n = stages.count[name]
        total = stages.encode_ns[name] + stages.add_ns[name]
        print(f"| {name} | {n} | {stages.encode_ns[name] / n / 1e3:.1f} | "
              f"{stages.add_ns[name] / n / 1e3:.1f} | {total / 1e6 / loop_s:.2f} |")  # fmt: skip
    records_s = (sum(stages.encode_ns.values()) + sum(stages.add_ns.values())) / 1e9
    flush_each_s = stages.flush_ns / 1e9 / max(stages.flushes, 1)
    other_s = stages.busy_s - records_s - stages.flush_ns / 1e9
    print(f"\nwriter thread CPU {stages.busy_s:.3f} s = {stages.busy_s / loop_s * 100:.2f} % "
          f"of a core per s of loop time: records (encode + write) {records_s:.3f} s, "
          f"{stages.flushes} flushes {stages.flush_ns / 1e9:.3f} s ({flush_each_s * 1e3:.2f} "
          f"ms each), the rest (waiting, queue, timers) {other_s:.3f} s")  # fmt: skip
    realtime = records_s / loop_s + flush_each_s / stages.flush_interval_s
    print(f"real-time estimate (records per s of loop time + a flush every "
          f"{stages.flush_interval_s:g} s): {realtime * 100:.2f} % of a core, without the "
          f"rest")  # fmt: skip
    each_us = stages.camera_jpeg_ns / max(stages.camera_jpegs, 1) / 1e3
    print(f"the frames' JPEG, the camera's (the twin's, on the loop's thread; not in the "
          f"writer's figures): {stages.camera_jpegs} frames, {each_us:.1f} us each, "
          f"{stages.camera_jpeg_ns / 1e6 / loop_s:.2f} ms per s of loop time")  # fmt: skip
    return 0
