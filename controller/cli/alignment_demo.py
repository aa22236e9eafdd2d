"""``tactile teleop`` (``tactile teleop``): the teleoperated alignment demo.

    teleop_demo.py [--task usb_c|usb_a|PATH] [--backend sim|real] [--script FILE]
                   [--autonomy] [--no-view] [--foxglove [--foxglove-host H] [--foxglove-port P]]
                   [--duration S] [--seed N] [--fast] [--set KEY=VALUE ...] --out DIR

The stick starts grasped, partly inserted (``scene.start_depth_m``, 2 mm) and aligned in the
simulated hole; after the grasp (about 2 s) the operator drives the arm with the gamepad
(deadman held) and watches the tilt torques (docs/USER_GUIDE.md: the manoeuvres and their signs).

* ``--backend sim`` (default): the simulated world in real time; the pad is a real one if SDL
  sees a game controller, else the scripted twin playing ``--script FILE``
  (drivers/sim/twins/pad_script.py) or the default script configs/teleop/alignment_demo.yaml.
  ``--fast`` runs a scripted demo as fast as the simulation goes (the view, if open, shows
  what it can and drops the rest).
* ``--backend real``: the configured devices, the same code.
* ``--autonomy``: the find-align-insert machine (controller ``align``, on the tilt torques
  the operator watches) from the trials' start; the pad overrides it at any moment and
  ``hand_back`` resumes autonomy from a phase fitting the contact state.
* The deadman is required for takeover and motion (a safety rule, not a setting); the e-stop latches
  until released and acknowledged; the commands pass the task's limits; an unplugged pad
  while in control trips the watchdog (a safe stop within the tick).
* The episode (every stream, docs/EPISODES.md) goes to ``DIR/episode.mcap``; the live view
  (a window, its own process) shows it as it is written; ``--foxglove`` serves the same
  streams on ws://HOST:PORT (a port already taken: one line, exit 2).

Times printed (the timeline, the sign table) are seconds from the run's start, on its
clock. ``--duration S`` ends the demo after S s on that clock.

Exit: 0 when the demo ended (hand-back, the duration, the window closed); 130 / 143 on
SIGINT / SIGTERM after the safe stop; 2 for bad input; 1 if a device could not be reached
or the run ended in a fault (a watchdog trip: an unplugged pad while the operator drives,
late ticks; after the safe stop, one line naming it; a simulated real-time run on a loaded
machine is told to need an idle core, controller/cli/run_outcome.py).
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import os
import signal
from collections.abc import Callable
from contextlib import ExitStack
from pathlib import Path
from typing import Any

from controller.cli.outputs import check_output_folder
from controller.cli.run_outcome import fault_exit, pace_line, signal_exit
from controller.cli.support import (
    ToolError,
    add_override_argument,
    integer,
    number,
    run_tool,
)
from controller.cli.teleop_signs import Manoeuvre, SignCheck, manoeuvres, measured_signs
from controller.episode import Episode, read_episode
from controller.episode.session import EPISODE_FILE, EpisodeRecording
from controller.insertion.teleop_only import TeleopOnlyMachine
from controller.run import RunOutcome, run_task
from controller.run.controllers import CONTROLLERS, Controller
from controller.run.task import Task, TaskConfig, load_task
from core.config import CONFIG_ROOT
from core.sensor_profile import sensor_profile
from core.subcommands import job_prog
from drivers import registry

DEFAULT_SCRIPT = CONFIG_ROOT / "teleop" / "alignment_demo.yaml"
START_DEPTH_M = 0.002
"""How far the plug's tip starts below the board surface (partly inserted)."""
TELEOP_CONTROLLER = "teleop"
AUTONOMY_CONTROLLER = "align"
"""The machine ``--autonomy`` runs: the demo's cues (the tilt torques) closed in a loop, whose
hand-back resumes from the contact state (APPROACH, SEARCH, ALIGN) and whose timeout the
demo's ``--duration`` sets (``machine.timeouts.total_s``)."""


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog=job_prog("teleop_demo"), description=__doc__.splitlines()[0]
    )
    parser.add_argument("--task", default="usb_c", help="usb_c (default), usb_a or a task YAML")
    parser.add_argument("--backend", choices=("sim", "real"), default="sim")
    parser.add_argument("--script", type=Path, help="a gamepad script for the simulated pad")
    parser.add_argument("--autonomy", action="store_true", help="run the align machine")
    parser.add_argument("--no-view", dest="view", action="store_false", help="no window")
    parser.add_argument("--foxglove", action="store_true", help="serve the streams live")
    parser.add_argument("--foxglove-host", default="127.0.0.1")
    parser.add_argument("--foxglove-port", type=integer(0, 65535), default=8765)
    parser.add_argument("--duration", type=number(5.0, 3600.0, "s"), default=600.0,
                        help="the longest the demo runs, s (default 600)")  # fmt: skip
    parser.add_argument("--seed", type=integer(0, 2**31 - 1), default=0)
    parser.add_argument("--fast", action="store_true",
                        help="scripted sim only: as fast as the simulation goes")  # fmt: skip
    add_override_argument(parser, "override a task key by dotted path (repeatable)")
    parser.add_argument("--out", type=Path, required=True, help="output folder (new or empty)")
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.fast and args.backend == "real":
        parser.error("argument --fast: only with --backend sim")
    if args.script is not None and args.backend == "real":
        parser.error("argument --script: the real backend reads the real pad")
    return run_tool("teleop_demo", lambda: _run(args))


def demo_overrides(args: argparse.Namespace) -> list[str]:
    """The task overrides the demo needs, before the user's ``--set``: the duration and
    (without ``--autonomy``, in simulation) the partly inserted start."""
    overrides = [f"machine.timeouts.total_s={args.duration}"]
    if not args.autonomy and args.backend == "sim":
        overrides.append(f"scene.start_depth_m={START_DEPTH_M}")
    return [*overrides, *args.overrides]


def _run(args: argparse.Namespace) -> int:
    task = load_task(args.task, demo_overrides(args), args.backend)
    check_output_folder(args.out, [task.path, args.script], option="--out")
    if args.out.exists() and any(args.out.iterdir()):
        raise ToolError(f"--out '{args.out}': the folder is not empty")
    if task.config.devices.gamepad is None:
        raise ToolError(f"{task.path}: key 'devices.gamepad': the demo needs a gamepad")
    script = None
    if args.backend == "sim" and (
        args.script or args.fast or not registry.real_pad_attached()
    ):  # a script plays the simulated pad (the registry loads it), which a real run never loads
        mapping = pad_mapping(task)
        script = registry.load_pad_script(
            args.script or DEFAULT_SCRIPT, mapping.axes, mapping.buttons
        )
    created = not args.out.exists()
    args.out.mkdir(parents=True, exist_ok=True)
    try:
        return run_demo(task, args, script)
    except BaseException:  # nothing recorded yet (a stream that cannot listen, no devices)
        if created and not any(args.out.iterdir()):
            args.out.rmdir()  # no empty folder left that looks like a run's
        raise


def run_demo(task: Task, args: argparse.Namespace, script: Any) -> int:
    """Run the demo (see the module doc); the exit code."""
    machines: list[Any] = []
    table = controller_table(machines)
    controller = AUTONOMY_CONTROLLER if args.autonomy else TELEOP_CONTROLLER
    listeners: list[Any] = []
    view = None
    quit_asked: list[bool] = []
    with ExitStack() as stack:  # the view and the stream end after the recording has closed
        if args.foxglove:
            from controller.view.live_stream import FoxgloveLiveStream, LiveStreamError

            try:
                stream = FoxgloveLiveStream(args.foxglove_host, args.foxglove_port)
            except LiveStreamError as error:
                raise ToolError(str(error)) from None
            stack.callback(stream.close)
            listeners.append(stream)
            print(f"teleop_demo: Foxglove live stream on {stream.url} (Open connection -> "
                  "Foxglove WebSocket; layout docs/foxglove/episode_layout.json)")  # fmt: skip
        if args.view:
            from controller.view.feed import ViewFeed
            from controller.view.window import LiveView

            view = LiveView(mapping_lines(task), args.out)
            listeners.append(ViewFeed(view.offer, sensor_profile(task.tactile_model).mm_per_px))
            view.start()
            stack.callback(view.close)
            view.watch(_on_view_command(machines, quit_asked))
        recording = EpisodeRecording(
            args.out / EPISODE_FILE,
            task.raw,
            task=task.config.task,
            task_file=task.path,
            overrides=task.overrides,
            seed=args.seed,
            controller=controller,
            backend=args.backend,
            calibration=task.calibration,
            listeners=listeners,
        )
        try:
            outcome = run_task(
                task,
                controller,
                args.seed,
                backend=args.backend,
                realtime=not args.fast,
                paced=True,
                controllers=table,
                prepare=_pad_preparation(task, script),
                episode=recording,
                max_duration_s=args.duration,
            )
        except BaseException as error:
            recording.close({"error": f"{type(error).__name__}: {error}"})
            raise
        loop = outcome.loop
        recording.close({"reason": loop.reason, "message": loop.message,
                         "phase": loop.phase.value, "error": ""})  # fmt: skip
    print(summary(outcome, view))
    if script is not None and not args.autonomy:
        print(sign_table(read_episode(args.out / EPISODE_FILE), manoeuvres(script)))
    print(f"teleop_demo: episode {args.out / EPISODE_FILE}")
    if not quit_asked:
        kept = f"the episode is complete up to then: {args.out / EPISODE_FILE}"
        stopped = signal_exit("teleop_demo", outcome.loop, kept)
        if stopped is not None:
            return stopped
    return fault_exit("teleop_demo", outcome.loop)


def controller_table(machines: list[Any]) -> dict[str, Controller]:
    """The run path's controllers plus the demo's ``teleop`` (``TeleopOnlyMachine`` on the
    estimator as it is); each machine built is appended to ``machines`` (the view's re-zero
    key reaches it there)."""

    def teleop_machine(config: TaskConfig) -> Any:
        machines.append(TeleopOnlyMachine(config.machine, config.plug, config.hole))
        return machines[-1]

    return {**CONTROLLERS, TELEOP_CONTROLLER: Controller(teleop_machine, lambda e, w, s: e)}


def _on_view_command(machines: list[Any], quit_asked: list[bool]) -> Callable[[str], None]:
    """The view's keys: 'quit' (or the window closed) ends the run as Ctrl-C does, through
    the loop's signal path (a safe stop within one period); 'rezero' asks the demo machine."""

    def on_command(command: str) -> None:
        if command == "quit":
            quit_asked.append(True)
            os.kill(os.getpid(), signal.SIGINT)
        elif command == "rezero":
            if machines and hasattr(machines[0], "request_rezero"):
                machines[0].request_rezero()
            else:
                print("teleop_demo: re-zero: only without --autonomy (the machine re-zeroes)")
        elif command.startswith("screenshot "):
            print(f"teleop_demo: saved {command.split(' ', 1)[1]}")
        elif command.startswith("error "):
            print(f"teleop_demo: the view could not open its window ({command[6:]}); the "
                  "demo goes on without it (--no-view to skip it)")  # fmt: skip

    return on_command


def _pad_preparation(task: Task, script: Any) -> Callable[[registry.DeviceSet], Any]:
    """The run's ``prepare``: play ``script`` on the simulated pad, or (simulation without a
    script) put the real pad into the simulated world; nothing on the real backend."""

    def prepare(device_set: registry.DeviceSet) -> registry.DeviceSet | None:
        if device_set.world is None:
            return None
        if script is not None:
            twin: Any = device_set.devices.gamepad  # the simulated pad (drivers/sim/twins)
            twin.play(script)
            return None
        pad: Any = registry.load_device(  # on the world's clock, as every device of the run
            task.device_files["gamepad"], "real", kind="gamepad", clock=device_set.clock
        )
        devices = dataclasses.replace(device_set.devices, gamepad=pad)
        return dataclasses.replace(device_set, devices=devices)

    return prepare


def pad_mapping(task: Task) -> Any:
    """The gamepad's mapping (its device file's ``axes`` and ``buttons`` by action)."""
    return registry.load_device_config(task.device_files["gamepad"], "real", "gamepad").config


def mapping_lines(task: Task) -> list[str]:
    """The pad's mapping as the view lists it."""
    config = pad_mapping(task)
    lines = [f"{action}: {b.axis}{' (inverted)' if b.invert else ''}"
             for action, b in config.axes.items()]  # fmt: skip
    lines.append(", ".join(f"{action}: {button}" for action, button in config.buttons.items()))
    return [" | ".join(lines[:2]), " | ".join(lines[2:4]), *lines[4:]]


def sign_table(episode: Episode, script: list[Manoeuvre]) -> str:
    """Each scripted manoeuvre, the torque it drives, the expected sign and the change
    the episode recorded, with its unit (docs/USER_GUIDE.md, "Signs")."""
    lines = ["manoeuvre (script s)          torque  expected  measured change        ok"]
    for check in measured_signs(episode, script):
        m = check.manoeuvre
        change = f"{check.change:+.2e} {check.unit}"
        lines.append(f"{m.action} {m.value:+.2f} ({m.start_s:5.1f}-{m.end_s:5.1f})"
                     f"{'':8}{m.torque}  {m.expected_sign:+d}        {change:<22} "
                     f"{verdict(check)}")  # fmt: skip
    return "\n".join(lines)


def verdict(check: SignCheck) -> str:
    """'yes', 'NO', or 'not reached' (the demo ended before the manoeuvre)."""
    if math.isnan(check.change):
        return "not reached"
    return "yes" if check.ok else "NO"


def summary(outcome: RunOutcome, view: Any) -> str:
    """The phase timeline, how the demo ended, and the loop's timing."""
    lines = [f"{'t (s)':>8}  phase change (reason)"]
    lines += [f"{t.t_s:8.2f}  {t.source.value} -> {t.target.value} ({t.reason})"
              for t in outcome.transitions]  # fmt: skip
    stats = outcome.loop.stats
    lines.append(f"ended: {outcome.loop.reason} ({outcome.loop.message}), phase "
                 f"{outcome.loop.phase.value}")  # fmt: skip
    lines.append(f"loop: {stats.ticks} ticks, {stats.overruns} overruns, period p99 "
                 f"{stats.period_p99_s * 1e3:.2f} ms")  # fmt: skip
    pace = pace_line(outcome.devices.clock)
    if pace is not None:
        lines.append(pace)
    if view is not None:
        lines.append(f"view: {view.offered} frames offered, {view.dropped} dropped")
    return "\n".join(lines)
