"""Speed of the gel model (``GelModel.solve``) on one thread, per gel profile and object.

A quasi-static sequence: the grip force, the shear, the tilt torques and the in-plane
torque vary smoothly and slowly (within what the contact holds, with partial slip), as in
a grasp or an insertion scene. Each step is solved twice: warm, starting from the previous
step's solution (``start=``), as a scene does, and cold (no start). Reported: median and
p90 ms per solve over the sequence, and the share of each stage (normal contact,
tangential contact, layer convolution, camera) from a profiled pass.

    python -m evaluation bench_gel [--steps 240] [--repeats 3]

The script limits OpenMP, OpenBLAS and MKL to one thread before NumPy loads.
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import time

import numpy as np

from drivers.sim.gel.model import GelModel, Wrench
from drivers.sim.gel.profile import SHAPES
from evaluation.common.machine_info import describe_machine
from evaluation.common.sim_setup import SENSORS, gel_profile

STAGES = {
    "normal": "solve_normal",
    "tangential": "solve_tangential",
    "layer": "surface_displacement_m",
    "camera": "image_field_px",
}

from controller.cli.support import integer, run_tool  # noqa: E402


def sequence(steps: int) -> list[tuple[float, Wrench]]:
    """(grip force N, wrench) along a slow, smooth loading path."""
    t = np.linspace(0.0, 1.0, steps)
    grip = 8.0 + 2.0 * np.sin(2 * np.pi * t)
    return [
        (
            float(g),
            Wrench(
                fx=float(2.0 * np.sin(2 * np.pi * s)),
                fy=float(0.5 * np.sin(4 * np.pi * s)),
                fz=0.0,
                tau_x=float(0.004 * np.sin(2 * np.pi * s + 1.0)),
                tau_y=float(0.002 * np.cos(2 * np.pi * s)),
                tau_z=float(0.004 * np.sin(6 * np.pi * s)),
            ),
        )
        for g, s in zip(grip, t, strict=True)
    ]


def run(model: GelModel, steps: list[tuple[float, Wrench]], warm: bool) -> np.ndarray:
    """Seconds per solve along ``steps``."""
    times = np.empty(len(steps))
    state = None
    for i, (grip, wrench) in enumerate(steps):
        begin = time.perf_counter()
        state = model.solve(grip, wrench, start=state if warm else None)
        times[i] = time.perf_counter() - begin
    return times


def stage_shares(model: GelModel, steps: list[tuple[float, Wrench]]) -> dict[str, float]:
    """Share of each stage in the profiled time of a warm pass."""
    profiler = cProfile.Profile()
    profiler.enable()
    run(model, steps, warm=True)
    profiler.disable()
    stats = pstats.Stats(profiler).stats  # {(file, line, name): (cc, nc, tt, ct, callers)}
    total = sum(ct for (_, _, name), (*_, ct, _) in stats.items() if name == "solve")
    return {
        stage: sum(ct for (_, _, name), (*_, ct, _) in stats.items() if name == function) / total
        for stage, function in STAGES.items()
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--steps", type=integer(200, 1_000_000), default=240, help="solves per sequence (>= 200)"
    )
    parser.add_argument(
        "--repeats", type=integer(1, 10_000), default=3, help="timed passes (best median)"
    )
    args = parser.parse_args(argv)
    return run_tool("bench_gel", lambda: bench(args))


def bench(args: argparse.Namespace) -> int:
    steps = sequence(args.steps)
    print(f"Machine: {describe_machine('1 thread (OMP/OpenBLAS/MKL 1)')}.")
    print(f"{args.steps} solves per sequence, best of {args.repeats} passes; ms per solve.\n")
    header = "| profile | object | grid | warm median | warm p90 | cold median | cold p90 |"
    print(header + " normal | tangential | layer | camera |")
    print("|" + "---|" * (header.count("|") - 1 + len(STAGES)))
    for sensor in SENSORS:
        profile = gel_profile(sensor)
        for kind, shape in SHAPES.items():
            model = GelModel(profile, shape)
            run(model, steps[:20], warm=True)  # caches and first-call costs
            cells = []
            for warm in (True, False):
                passes = [run(model, steps, warm) * 1e3 for _ in range(args.repeats)]
                best = min(passes, key=np.median)
                cells += [f"{np.median(best):.2f}", f"{np.percentile(best, 90):.2f}"]
            shares = stage_shares(model, steps)
            rows, cols = model.grid.shape
            print(
                f"| {profile.name} | {kind} | {rows}x{cols} | "
                + " | ".join(cells)
                + " | "
                + " | ".join(f"{100 * shares[s]:.0f}%" for s in STAGES)
                + " |"
            )
    print("\nStage shares: cumulative profiled time of each stage in a warm pass.")
    return 0
