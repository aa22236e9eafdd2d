"""The episode tools: ``replay SUBCOMMAND EP ...`` (tactile replay, the installed
``tactile replay``; docs/EPISODES.md, "Tools").

    replay summary EP                      topics, counts, rates, duration, outcome,
                                           transitions, drops
    replay plot EP --out PNG               the trial summary's chart, made from the episode
    replay reestimate EP --method NAME|PATH [--out CSV]
                                           re-run an estimator configuration on the logged
                                           frames; R^2 and RMSE per axis against the truth
                                           (simulation) and against the logged estimates
    replay export EP [EP ...] --lerobot DIR [--task TEXT]
                                           a LeRobot v3.0 dataset of the episodes
    replay export EP --rerun OUT.rrd       a Rerun recording of the episode (the ``rerun``
                                           extra): scalars, texts, images, fields, frames
    replay repair EP [--out OUT]           finish a file left by a killed process

EP is an episode file (MCAP, ``episode.mcap`` in a run's folder). A file cut short by a
killed process (no footer) is refused, saying how much of it holds whole records, unless
``--allow-truncated`` (then what was read is used, with one warning line); ``repair`` makes
a finished copy. A file damaged in the middle (bytes overwritten) is read past the damage
(controller/episode/scan.py): the lost byte ranges are named, and the file is refused in the
same way unless ``--allow-damaged`` (the same switch); ``repair`` keeps every readable
chunk. Outputs are checked before any work, never written over an input, and
written atomically (a temporary file or folder renamed into place when complete). Expected
failures (a missing, foreign or truncated file, a bad configuration, an output that cannot
be written) print one line ``replay: error: ...`` and exit with code 2; SIGINT and SIGTERM
exit with 130 and 143 (controller/cli/support.py).
"""

from __future__ import annotations

import argparse
import csv
import itertools
import math
import sys
import time
from collections.abc import Iterator
from pathlib import Path

from controller.cli.estimate import CSV_COLUMNS, csv_row
from controller.cli.outputs import (
    atomic_file,
    atomic_text,
    check_output_file,
    check_output_folder,
)
from controller.cli.support import (
    ToolError,
    distinct,
    nonblank,
    resolved_config_path,
    run_tool,
)
from controller.episode import Episode, EpisodeError, read_episode
from controller.episode.repair import repair as repair_file
from controller.episode.topics import LOOP_TICK
from controller.replay import episode_streams, reestimation
from controller.replay.episode_chart import write_episode_chart
from controller.replay.episode_summary import CRC_NOTE, summary_lines
from controller.replay.lerobot_alignment import AlignedEpisode, AlignmentError, align
from controller.replay.lerobot_dataset import DatasetEpisode, write_dataset
from controller.replay.rerun_export import LOOP_TIMELINE, RerunMissing, rerun_sdk, write_recording
from controller.tactile import estimator_for_sensor
from controller.tactile.settings import sensor_estimator
from core.sensor_profile import sensor_profile
from core.subcommands import job_prog

PROG = "replay"


def _warn(message: str) -> None:
    print(f"{PROG}: warning: {message}", file=sys.stderr)


def open_episode(path: Path, allow_truncated: bool = False) -> Episode:
    """The episode at ``path``; ToolError (one line) if it is missing, not an episode, cut
    short or damaged (unless ``allow_truncated``: then one warning line)."""
    if path.is_dir():
        raise ToolError(f"episode '{path}' is a folder; expected an episode file (.mcap)")
    try:
        episode = read_episode(path)
    except EpisodeError as exc:
        raise ToolError(str(exc)) from None
    problems = []  # (what is wrong, the switch that accepts it)
    messages = sum(episode.counts.values())
    expected = f" of the {episode.expected_messages} written" if episode.expected_messages else ""
    if episode.damaged:
        problems.append(
            (
                f"episode '{path}' is damaged: {episode.lost_bytes} bytes could not be read "
                f"({episode.lost_text()}); read {messages} messages{expected} from the rest",
                "--allow-damaged",
            )
        )
    if not episode.finished:
        _, last = episode.time_range_s()
        until = f", up to {last:.3f} s on the loop clock" if math.isfinite(last) else ""
        problems.append(
            (
                f"episode '{path}' is truncated (no footer: the process writing it was killed?): "
                f"read {episode.read_bytes} of {episode.size_bytes} bytes, {messages} messages"
                f"{until}",
                "--allow-truncated",
            )
        )
    if episode.unverified_change:
        _warn(f"episode '{path}': the data section's CRC does not match: {CRC_NOTE}")
    for problem, switch in problems:
        if not allow_truncated:
            raise ToolError(
                f"{problem}; finish it with 'replay repair {path}' (a copy of what is "
                f"readable), or pass {switch}"
            )
        _warn(problem)
    return episode


def summary(args: argparse.Namespace) -> int:
    print("\n".join(summary_lines(open_episode(args.episode, args.allow_truncated))))
    return 0


def plot(args: argparse.Namespace) -> int:
    if args.out.suffix.lower() != ".png":
        raise ToolError(f"--out '{args.out}': expected a .png file (the chart is a PNG)")
    check_output_file(args.out, [args.episode])
    episode = open_episode(args.episode, args.allow_truncated)
    if not episode.counts.get(LOOP_TICK.name):
        raise ToolError(
            f"episode '{args.episode}' has no control ticks ({LOOP_TICK.name}): the run ended "
            "before its first tick; nothing to plot"
        )
    write_episode_chart(episode, args.out)
    print(f"{PROG}: wrote {args.out}")
    return 0


def _score_lines(title: str, scores: list[reestimation.AxisScore], unit: str) -> list[str]:
    lines = [title]
    for s in scores:
        exact = f", {s.exact} of {s.samples} frames identical" if s.exact is not None else ""
        lines.append(
            f"  {s.axis}: R^2 {s.r2:.6f}, RMSE {s.rmse:.6g} {unit} over {s.samples} frames{exact}"
        )
    return lines


def reestimate(args: argparse.Namespace) -> int:
    method_file = resolved_config_path(args.method, "estimators")
    if args.out is not None:
        check_output_file(args.out, [args.episode, method_file])
    episode = open_episode(args.episode, args.allow_truncated)
    try:
        run = reestimation.run_estimator(episode)
        profile = sensor_profile(run.sensor)
        _, config = sensor_estimator(profile, str(args.method))
        calibration = reestimation.calibration_for(run, config)
        estimator = estimator_for_sensor(profile, args.method, calibration)
        new = reestimation.reestimate(episode, estimator, time.perf_counter)
    except reestimation.ReestimationError as exc:
        raise ToolError(f"episode '{args.episode}': {exc}") from None
    except ValueError as exc:  # a frame the estimator refuses (its size, its type)
        raise ToolError(f"episode '{args.episode}': re-estimation failed: {exc}") from None
    image_format = episode.info.get("tactile_image_format", "unknown")
    lines = [
        f"re-estimated {len(new.estimates)} frames of '{args.episode}' with "
        f"'{estimator.config_name}' (the run's: '{run.estimator}', sensor {run.sensor}; "
        f"frames logged as {image_format}; "
        + (
            "with the run's calibration, N*m and N)"
            if calibration is not None
            else "raw: "
            + (
                "the run applied no calibration)"
                if run.calibration is None
                else "the run's calibration is for another configuration)"
            )
        )
    ]
    truth = episode_streams.truth(episode)
    if truth is not None:
        lines += _score_lines(
            "against the truth (/sim/truth, the gel's torque on the plug; fit truth ~ slope * "
            "estimate + offset over the frames estimated against a reference):",
            reestimation.against_truth(new, truth),
            "N*m",
        )
    logged = episode_streams.estimates(episode)
    if len(logged.push_index) and logged.calibrated != (calibration is not None):
        lines.append(
            "against the logged estimates: not compared (they are "
            + ("calibrated, N*m; these are raw)" if logged.calibrated else "raw; these are N*m)")
        )
    elif len(logged.push_index):
        lines += _score_lines(
            "against the logged estimates (/tactile/wrench; no fit):",
            reestimation.against_logged(new, logged),
            "(N*m)" if calibration is not None else "(raw)",
        )
    if args.out is not None:
        with atomic_text(args.out, newline="") as handle:
            writer = csv.writer(handle)
            writer.writerow(CSV_COLUMNS)
            for push, t_s, found, ms in zip(
                new.push_index, new.t_s, new.estimates, new.latency_ms, strict=True
            ):
                writer.writerow(csv_row(int(push), float(t_s), found, float(ms)))
        lines.append(f"wrote {len(new.estimates)} rows to {args.out}")
    print("\n".join(lines))
    return 0


def _task_sentence(episode: Episode, given: str | None) -> str:
    return given if given is not None else f"insert the {episode.info.get('task', 'usb')} plug"


def export(args: argparse.Namespace) -> int:
    distinct(build_parser(), "EP", [str(p.resolve()) for p in args.episodes])
    if args.rerun is not None:
        return export_rerun(args)
    check_output_folder(args.lerobot, args.episodes, "--lerobot", must_not_exist=True)
    aligned = _aligned_episodes(args.episodes, args.allow_truncated, args.task)
    first = next(aligned)  # the dataset's rate, frame size and window
    fps, frame_hw, window = first.fps, first.frame_hw, first.window
    drift_s = 0.0

    def each() -> Iterator[DatasetEpisode]:
        nonlocal drift_s
        for item in itertools.chain([first], aligned):
            drift_s = max(drift_s, item.drift_s)
            yield item.dataset  # its frames are read while the video is written, then freed

    try:
        written = write_dataset(each(), args.lerobot, fps, frame_hw)
    except ValueError as exc:  # an episode the dataset cannot hold (named in the message)
        raise ToolError(f"--lerobot '{args.lerobot}': {exc}") from None
    print(
        f"{PROG}: wrote a LeRobot v3.0 dataset of {written.episodes} episodes, "
        f"{written.frames} frames at {written.fps} fps (one row per tactile frame; {window} "
        f"control ticks per frame; capture times at most {drift_s:.3f} s from the nominal "
        f"timestamps) to {args.lerobot}"
    )
    return 0


def export_rerun(args: argparse.Namespace) -> int:
    """``export EP --rerun OUT.rrd``: one episode, written to a temporary file beside OUT
    and renamed when complete."""
    if len(args.episodes) != 1:
        raise ToolError(f"--rerun: expected one episode, got {len(args.episodes)}")
    if args.task is not None:
        raise ToolError("--task: only with --lerobot (a Rerun recording has no task sentence)")
    if args.rerun.suffix.lower() != ".rrd":
        raise ToolError(f"--rerun '{args.rerun}': expected a .rrd file (a Rerun recording)")
    try:
        rerun_sdk()
    except RerunMissing:
        raise ToolError(
            "--rerun needs rerun-sdk, not installed: pip install -e '.[rerun]' (the 'rerun' extra)"
        ) from None
    check_output_file(args.rerun, args.episodes, "--rerun")
    episode = open_episode(args.episodes[0], args.allow_truncated)
    with atomic_file(args.rerun) as temporary:
        counts = write_recording(episode, temporary)
    rows = ", ".join(f"{n} {kind}" for kind, n in counts.items())
    print(f"{PROG}: wrote a Rerun recording ({rows}; timeline '{LOOP_TIMELINE}') to {args.rerun}")
    return 0


def _aligned_episodes(
    paths: list[Path], allow_truncated: bool, task: str | None
) -> Iterator[AlignedEpisode]:
    """Each episode read and aligned only when the export asks for it (one in memory at a
    time); ToolError naming the file for one the first one's dataset cannot hold (another
    camera rate, frame size, or loop rate: the window of ticks per frame)."""
    first: AlignedEpisode | None = None
    for path in paths:
        episode = open_episode(path, allow_truncated)
        try:
            item = align(episode, _task_sentence(episode, task))
        except AlignmentError as exc:
            raise ToolError(f"episode '{path}': {exc}") from None
        del episode  # the aligned episode's frames keep what they need
        if first is None:
            first = item
        elif (item.fps, item.frame_hw, item.window) != (first.fps, first.frame_hw, first.window):
            raise ToolError(
                f"episode '{path}': {item.fps} fps, frames {item.frame_hw}, "
                f"{item.window} control ticks per frame (loop {item.loop_rate_hz:.0f} Hz); the "
                f"first episode has {first.fps} fps, frames {first.frame_hw}, {first.window} "
                f"ticks per frame (loop {first.loop_rate_hz:.0f} Hz): one dataset holds one "
                "camera rate, frame size and loop rate; export them separately"
            )
        yield item


def repair(args: argparse.Namespace) -> int:
    out = args.out or args.episode.with_name(args.episode.stem + ".repaired.mcap")
    check_output_file(out, [args.episode], "--out")
    try:
        report = repair_file(args.episode, out)
    except EpisodeError as exc:
        raise ToolError(str(exc)) from None
    lost = f", {report.lost_bytes} bytes lost to damage" if report.lost_bytes else ""
    print(
        f"{PROG}: wrote {out}: {report.messages} messages from the {report.read_bytes} of "
        f"{report.source_bytes} bytes of '{args.episode}' that held whole records{lost}, "
        "marked incomplete"
    )
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog=job_prog(PROG), description="Tools for episode files (MCAP)."
    )
    commands = parser.add_subparsers(dest="command", required=True, metavar="SUBCOMMAND")

    def command(name: str, help_text: str, run) -> argparse.ArgumentParser:
        sub = commands.add_parser(name, help=help_text, description=help_text)
        sub.set_defaults(run=run)
        return sub

    def episode_argument(sub: argparse.ArgumentParser, truncated: bool = True) -> None:
        sub.add_argument("episode", type=Path, metavar="EP", help="episode file (.mcap)")
        if truncated:
            sub.add_argument(
                "--allow-truncated",
                "--allow-damaged",
                dest="allow_truncated",
                action="store_true",
                help="read a file cut short (no footer) or damaged: what is readable",
            )

    sub = command(
        "summary", "topics, counts, rates, duration, outcome, transitions, drops", summary
    )
    episode_argument(sub)
    sub = command("plot", "the trial summary's chart of the episode (PNG)", plot)
    episode_argument(sub)
    sub.add_argument("--out", type=Path, required=True, help="output PNG path")
    sub = command(
        "reestimate", "re-run an estimator configuration on the logged frames", reestimate
    )
    episode_argument(sub)
    sub.add_argument(
        "--method",
        required=True,
        type=nonblank("an estimator configuration's name or a YAML path"),
        help="estimator configuration: a name in configs/estimators or a YAML path",
    )
    sub.add_argument("--out", type=Path, default=None, help="CSV of the new estimates")
    sub = command(
        "export", "export episodes as a LeRobot v3.0 dataset or one as a Rerun recording", export
    )
    sub.add_argument("episodes", type=Path, nargs="+", metavar="EP", help="episode files")
    sub.add_argument(
        "--allow-truncated",
        "--allow-damaged",
        dest="allow_truncated",
        action="store_true",
        help="read files cut short (no footer) or damaged: what is readable",
    )
    target = sub.add_mutually_exclusive_group(required=True)
    target.add_argument("--lerobot", type=Path, help="new dataset folder")
    target.add_argument("--rerun", type=Path, metavar="OUT.rrd",
                        help="a Rerun recording of one episode (the 'rerun' extra)")  # fmt: skip
    sub.add_argument(
        "--task",
        default=None,
        type=nonblank("a task sentence, e.g. 'insert the usb_c plug'"),
        help="the task sentence of every episode (default: 'insert the TASK plug')",
    )
    sub = command("repair", "finish a file left by a killed process", repair)
    episode_argument(sub, truncated=False)
    sub.add_argument(
        "--out", type=Path, default=None, help="the finished copy (default: EP.repaired.mcap)"
    )
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    return run_tool(PROG, lambda: _run(args))


def _run(args: argparse.Namespace) -> int:
    """The subcommand; an episode's content that cannot be read (a message that does not
    decode, one without the fields the writer writes) is one line too."""
    try:
        return args.run(args)
    except EpisodeError as exc:
        raise ToolError(str(exc)) from None
