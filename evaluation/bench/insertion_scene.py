"""Speed of the simulated insertion scene (drivers/sim/scenes/insertion/) on one thread:
physics, gel solve and rendering, and optionally the tactile estimator, in a 100 Hz loop.

No controller: a scripted TCP trajectory streamed to the arm twin (``servo_pose``) at
100 Hz, built from the scene's TRUE draws (the hole, the board's tilt and the plug's pose
in the grasp: a benchmark may look; a controller may not): grasp the
plug, a tilted approach beside the opening, touch the surface, drag the tip over the
opening's edge, turn upright over the hole and insert to the floor. Every tick reads the
arm, the gripper and the newest tactile frame (25 Hz: the gel is solved and the frame
rendered once per new frame) and gives each new frame to the estimator. The estimator is
zeroed as the control loop zeroes it for the insertion machine (controller/loop.py): the
open gel from the task's ``loop.rezero_frames`` frames before the fingers close, the
reference from as many frames once the grasp has settled (until then a push only
captures). Reported: simulated seconds per wall second and per CPU second (the median over
runs), the frames, the final insertion depth and the largest contact force.

    python -m evaluation bench_insertion_scene [--task usb_c] [--runs 3] [--no-estimate]
        [--set KEY=VALUE ...] [--against CHECKOUT] [--fingerprint] [--profile]

The task's ``estimator:`` (null: the sensor's own, the default) is the estimator, as in a
trial; ``--set`` overrides any task key by its dotted path, checked as the task file is
(e.g. ``--set estimator=PATH.yaml`` to time another estimator).

``--against CHECKOUT``: instead of the timed runs in this process, each seed once here and
once in another checkout of the project (e.g. a git worktree at the base commit), each run
in a fresh process, the two sides alternating, with the ratio per seed and its median
(evaluation/bench/scene_pairs.py): a speed-up measured in one time window, under one load.

``--fingerprint``: after the timed runs, each seed again, untimed, with digests of its
frames, estimates and truth (evaluation/bench/run_fingerprint.py): two versions of the code
that print the same digests made the same runs bit for bit.

``--profile``: after the timed runs, one more run of the first seed under ``cProfile`` on
the CPU-time clock, its time split by part of the scene and its costliest functions
(evaluation/bench/scene_profile.py).

The script limits OpenMP, OpenBLAS and MKL to one thread before NumPy loads, and OpenCV to
one thread.
"""

from __future__ import annotations

import argparse
import math
import pstats
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import cv2
import mujoco
import numpy as np
from scipy.spatial.transform import Rotation

from controller.cli.support import add_override_argument, integer, run_tool
from controller.run import Task, load_task
from controller.tactile import TactileEstimator, estimator_for_sensor
from core.devices import Pose
from core.spatial import rpy_from_rotation
from drivers.registry import WorldSpec, build_device_set
from drivers.sim.scenes.insertion import InsertionSim
from drivers.sim.scenes.insertion.frames import S_IN_T
from evaluation.bench.run_fingerprint import RunFingerprint
from evaluation.bench.scene_pairs import check_checkout, print_pairs
from evaluation.bench.scene_profile import part_clock, part_times, profile_call, top_functions
from evaluation.common.machine_info import describe_machine

RATE_HZ = 100.0
TILT_RAD = 0.15  # the tilted approach's tilt, about the hole's y
GRIP_FORCE_N = 40.0
TASKS = ("usb_c", "usb_a")


@dataclass(frozen=True)
class Waypoint:
    """The plug's tip at ``offset_x_m`` along the hole's x and ``height_m`` above the
    surface, the tool tilted by ``tilt_rad`` about the hole's y, reached ``duration_s``
    after the previous waypoint (linear in between)."""

    duration_s: float
    offset_x_m: float
    height_m: float
    tilt_rad: float


def script(half_width_m: float, depth_m: float) -> list[Waypoint]:
    """Approach tilted beside the opening, touch, drag over the edge, upright, insert."""
    beside = -(half_width_m + 0.002)
    return [
        Waypoint(1.0, beside, 0.004, TILT_RAD),  # tilted approach
        Waypoint(0.6, beside, -0.0015, TILT_RAD),  # touch: press about 1.5 mm into the wrist
        Waypoint(1.0, -half_width_m + 0.001, -0.0015, TILT_RAD),  # drag over the edge
        Waypoint(0.8, 0.0, 0.0, 0.0),  # upright over the hole
        Waypoint(1.5, 0.0, -(depth_m + 0.001), 0.0),  # insert to the floor
        Waypoint(0.4, 0.0, -(depth_m + 0.001), 0.0),  # settle
    ]


def tcp_for_tip(sim: InsertionSim, length_m: float, waypoint: Waypoint) -> Pose:
    """The TCP pose that puts the plug's tip (with a rigid wrist) where ``waypoint`` says, in
    the true board's frame H, the plug's axis tilted by the waypoint's tilt from H's normal
    about H's y, whatever the plug's pose in the grasp."""
    draw = sim.draw
    hole = draw.hole
    board = Rotation.from_euler("z", hole.yaw_rad) * Rotation.from_euler("xy", draw.board_tilt_rad)
    tip = np.array([hole.x_m, hole.y_m, hole.z_m]) + board.apply(
        [waypoint.offset_x_m, 0.0, waypoint.height_m]
    )
    # the nominal tool (rpy (pi, tilt, 0) in H) points its z along the wanted plug axis;
    # the grasped plug's axis and tip in T (S2T = S_IN_T) are turned onto that z
    nominal = board * Rotation.from_euler("xyz", (math.pi, waypoint.tilt_rad, 0.0))
    axis_t = S_IN_T @ draw.grasp.rotation() @ np.array([0.0, 1.0, 0.0])
    onto_z, _ = Rotation.align_vectors([[0.0, 0.0, 1.0]], [axis_t])
    tool = nominal * onto_z
    tip_t = S_IN_T @ draw.grasp.place(np.array([0.0, length_m, 0.0]))
    tcp = tip - tool.apply(tip_t)
    near = (math.pi, waypoint.tilt_rad, hole.yaw_rad)  # the script interpolates rpy
    return Pose(tuple(float(v) for v in tcp), rpy_from_rotation(tool, near))


@dataclass(frozen=True)
class RunResult:
    sim_s: float
    wall_s: float
    cpu_s: float
    frames: int
    depth_m: float
    max_contact_force_n: float
    digests: dict[str, str] | None = None  # with a fingerprint (run_fingerprint.py)

    @property
    def speed_x(self) -> float:
        """Simulated seconds per wall second."""
        return self.sim_s / self.wall_s

    @property
    def cpu_speed_x(self) -> float:
        """Simulated seconds per CPU second of this process (robust to a busy machine)."""
        return self.sim_s / self.cpu_s


def scripted_run(
    task: str,
    seed: int,
    estimate: bool,
    runner: Callable[[Callable[[], None]], object] = lambda drive: drive(),
    fingerprint: RunFingerprint | None = None,
    overrides: Sequence[str] = (),
) -> RunResult:
    """One scripted insertion (see the module docstring), timed from the first command;
    ``runner(drive)`` runs its timed part (e.g. under a profiler); ``fingerprint`` is fed
    every frame and estimate (its hashing is timed too); ``overrides``: ``KEY=VALUE`` on
    the task."""
    loaded = load_task(task, overrides)
    world = WorldSpec(loaded.scene, loaded.config.plug, loaded.config.hole, seed)
    sim = build_device_set(loaded.device_files, "sim", world).world
    estimator = (
        estimator_for_sensor(loaded.tactile_model, loaded.config.estimator) if estimate else None
    )
    for device in (sim.arm, sim.gripper, sim.tactile):
        device.connect()
    begin_wall, begin_cpu, begin_sim = time.perf_counter(), time.process_time(), sim.clock.now()
    loop = _Loop(sim, estimator, fingerprint)
    runner(lambda: _drive(loaded, sim, loop))
    sim.sync()
    wall, cpu = time.perf_counter() - begin_wall, time.process_time() - begin_cpu
    depth = float(sim.truth.arrays()["depth_m"][-1])
    return RunResult(
        sim.clock.now() - begin_sim,
        wall,
        cpu,
        loop.frames,
        depth,
        sim.truth.max_contact_force_n,
        None if fingerprint is None else fingerprint.digests(sim.truth),
    )


def _drive(loaded: Task, sim: InsertionSim, loop: _Loop) -> None:
    """The timed part: the grasp (zeroing the estimator as the control loop does), then the
    script's waypoints."""
    estimator, gripper = loop.estimator, sim.gripper
    zeroing_frames = loaded.config.loop.rezero_frames
    gripper.activate()
    if estimator is not None:
        estimator.capture_open(zeroing_frames)
    while loop.frames < zeroing_frames:  # the open gel (the same ticks without estimator)
        loop.tick(None)
    gripper.move(0.0, 0.05, GRIP_FORCE_N)
    while not gripper.read_status().holding:
        loop.tick(None)
    for _ in range(round(0.2 * RATE_HZ)):
        loop.tick(None)
    if estimator is not None:
        estimator.rezero(zeroing_frames)
    previous = sim.arm.read_status().tcp
    receptacle = loaded.scene.receptacle
    for waypoint in script(receptacle.width_m / 2, receptacle.depth_m):
        goal = tcp_for_tip(sim, loaded.config.plug.length_m, waypoint)
        ticks = max(1, round(waypoint.duration_s * RATE_HZ))
        for k in range(1, ticks + 1):
            share = k / ticks
            xyz = tuple(
                a + share * (b - a) for a, b in zip(previous.xyz_m, goal.xyz_m, strict=True)
            )
            rpy = tuple(
                a + share * (b - a) for a, b in zip(previous.rpy_rad, goal.rpy_rad, strict=True)
            )
            loop.tick(Pose(xyz, rpy))
        previous = goal


class _Loop:
    """One 100 Hz tick: read the arm, the gripper and the newest frame (estimating on a new
    one), send the servo target if any, sleep to the period's end."""

    def __init__(
        self,
        sim: InsertionSim,
        estimator: TactileEstimator | None,
        fingerprint: RunFingerprint | None = None,
    ) -> None:
        self.sim, self.estimator, self.fingerprint = sim, estimator, fingerprint
        self.frames = 0
        self._last_t: float | None = None

    def tick(self, target: Pose | None) -> None:
        sim = self.sim
        start = sim.clock.now()
        sim.arm.read_status()
        sim.gripper.read_status()
        frame = sim.tactile.read_latest(0.2)
        if frame.t_s != self._last_t:
            self._last_t = frame.t_s
            self.frames += 1
            estimate = None
            if self.estimator is not None:
                estimate = self.estimator.push(frame.image, frame.t_s)
            if self.fingerprint is not None:
                self.fingerprint.frame(frame.image)
                if estimate is not None:
                    self.fingerprint.estimate(estimate)
        if target is not None:
            sim.arm.servo_pose(target)
        sim.clock.sleep(start + 1.0 / RATE_HZ - sim.clock.now())


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--task", choices=TASKS, default="usb_c")
    parser.add_argument("--runs", type=integer(1, 1000), default=3, help="timed runs (median)")
    parser.add_argument("--seed", type=integer(0, 2**31 - 1), default=0, help="first seed")
    parser.add_argument(
        "--no-estimate", action="store_true", help="leave the tactile estimator out of the loop"
    )
    add_override_argument(parser, "override a task key by dotted path, e.g. estimator=PATH.yaml")
    parser.add_argument(
        "--against",
        type=Path,
        metavar="CHECKOUT",
        help="run each seed here and in this other checkout, alternating (scene_pairs.py)",
    )
    parser.add_argument(
        "--fingerprint",
        action="store_true",
        help="then run each seed again and print digests of its frames, estimates and truth",
    )
    parser.add_argument(
        "--profile",
        action="store_true",
        help="then profile one run of the first seed: CPU time by part of the scene",
    )
    args = parser.parse_args(argv)
    return run_tool("bench_insertion_scene", lambda: bench(args))


def bench(args: argparse.Namespace) -> int:
    estimate = not args.no_estimate
    other = None if args.against is None else check_checkout(args.against)
    load_task(args.task, args.overrides)  # a wrong key: one line, before any run
    cv2.setNumThreads(1)
    one_thread = "1 thread (cv2.setNumThreads(1), OMP/OpenBLAS/MKL 1)"
    print(f"Machine: {describe_machine(one_thread)}; MuJoCo {mujoco.__version__}.")
    what = "physics, gel, rendering" + (", estimation" if estimate else "")
    changed = "".join(f", {override}" for override in args.overrides)
    print(f"Task {args.task}{changed}, {what}; {args.runs} runs (seeds {args.seed}..).\n")
    seeds = range(args.seed, args.seed + args.runs)
    if other is not None:
        options = [
            "--task",
            args.task,
            *(["--no-estimate"] if args.no_estimate else []),
            *(part for override in args.overrides for part in ("--set", override)),
        ]
        print_pairs(other, seeds, options)
    else:
        timed_runs(args.task, seeds, estimate, args.overrides)
    if args.fingerprint:
        print("\n| seed | frames | estimates | truth |")
        print("|---|---|---|---|")
        for seed in seeds:
            digests = scripted_run(
                args.task, seed, estimate, fingerprint=RunFingerprint(), overrides=args.overrides
            ).digests
            assert digests is not None
            print(f"| {seed} | {digests['frames']} | {digests['estimates']} | {digests['truth']} |")
    if args.profile:
        print_profile(args.task, args.seed, estimate, args.overrides)
    return 0


def timed_runs(task: str, seeds: range, estimate: bool, overrides: Sequence[str]) -> None:
    """The timed runs in this process: a row each, then the medians."""
    print("| seed | sim s | wall s | x real time | CPU s | x per CPU s | frames | depth mm |")
    print("|---|---|---|---|---|---|---|---|")
    results = []
    for seed in seeds:
        r = scripted_run(task, seed, estimate, overrides=overrides)
        results.append(r)
        print(
            f"| {seed} | {r.sim_s:.2f} | {r.wall_s:.2f} | {r.speed_x:.1f} | {r.cpu_s:.2f} | "
            f"{r.cpu_speed_x:.1f} | {r.frames} | {r.depth_m * 1e3:.2f} |",
            flush=True,
        )
    median = float(np.median([r.speed_x for r in results]))
    median_cpu = float(np.median([r.cpu_speed_x for r in results]))
    print(
        f"\nMedian: {median:.1f} x real time (simulated s per wall s); {median_cpu:.1f} x per "
        "CPU second of the process (the same on an idle core; lower wall figures mean a busy "
        "machine)."
    )


def print_profile(task: str, seed: int, estimate: bool, overrides: Sequence[str] = ()) -> None:
    """Two more runs of ``seed``: one with the parts' timers (the split), one under the
    profiler (its top functions)."""
    with part_clock() as seconds:
        run = scripted_run(task, seed, estimate, overrides=overrides)
    print(
        f"\nSeed {seed}'s timed part by part of the scene (timers around each part's entry "
        f"points, exclusive of the parts it calls): {run.cpu_s:.3f} CPU s for "
        f"{run.sim_s:.2f} simulated s.\n"
    )
    print("| part | CPU s | share |")
    print("|---|---|---|")
    rest = run.cpu_s - sum(seconds.values())
    for part, part_s in sorted(
        [*seconds.items(), ("loop and the rest", rest)], key=lambda p: -p[1]
    ):
        print(f"| {part} | {part_s:.3f} | {100 * part_s / run.cpu_s:.0f} % |")
    profiles: list[pstats.Stats] = []
    run = scripted_run(
        task,
        seed,
        estimate,
        lambda drive: profiles.append(profile_call(drive)),
        overrides=overrides,
    )
    print(
        f"\nThe same under cProfile on the CPU clock ({run.cpu_s:.2f} CPU s: the profiler slows "
        "Python-heavy parts most), by part and by function:\n"
    )
    print("| part | CPU s | share |")
    print("|---|---|---|")
    for part in part_times(profiles[0]):
        print(f"| {part.part} | {part.seconds:.3f} | {100 * part.share:.0f} % |")
    print("\n| function | calls | own CPU s | part |")
    print("|---|---|---|---|")
    for where, calls, own_s, part_name in top_functions(profiles[0], 15):
        print(f"| `{where}` | {calls} | {own_s:.3f} | {part_name} |")
