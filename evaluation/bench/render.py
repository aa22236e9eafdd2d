"""Speed of the simulated tactile camera's image renderer, 320 x 240, on one thread.

Median and p90 ms per rendered frame of ``drivers.sim.render.gel_renderer.GelRenderer`` for a coarse
48 x 64 field (a physics grid of 5 px cells) and a full-resolution 240 x 320 field, without
effects, with all the static effects (pixel noise, lighting drift, blur, marker dropout,
occlusion) and with motion blur; then the stages of the plain coarse render, and the exact
spline renderer (``MarkerImageRenderer``) for comparison. The cases are timed in turn within
each round, so a load change on the machine affects them alike.

    python -m evaluation bench_render [--repeats 200]

The script limits OpenMP, OpenBLAS and MKL to one thread before NumPy loads.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable

import cv2
import numpy as np

from drivers.sim.render.field_inverse import BackwardMapper
from drivers.sim.render.gel_pattern import marker_coverage, marker_lattice, reflectance, speckle
from drivers.sim.render.gel_renderer import GelRenderer
from drivers.sim.render.image_effects import ImageEffects
from drivers.sim.render.image_warp import SplineWarper
from drivers.sim.render.lighting import led_shading, shade
from drivers.sim.render.marker_images import MarkerImageRenderer, smooth_random_field
from evaluation.common.machine_info import describe_machine

SHAPE_HW = (240, 320)
GRIDS = {"48x64": (48, 64), "240x320": SHAPE_HW}
STATIC_EFFECTS = ImageEffects(
    noise_grey=2.0,
    drift_gain_per_level=(0.02, -0.01, 0.015),
    drift_gradient_grey_per_level=5.0,
    blur_sigma_px=0.8,
    marker_dropout_fraction=0.1,
    occlusion_count=2,
)
from controller.cli.support import integer, run_tool  # noqa: E402

N_FIELDS = 8


def fields(grid_hw: tuple[int, int]) -> list[np.ndarray]:
    """Smooth random forward fields of 2 px peak at the grid's resolution (area means)."""
    rng = np.random.default_rng(2024)
    full = [smooth_random_field(SHAPE_HW, 2.0, rng) for _ in range(N_FIELDS)]
    return [cv2.resize(f, grid_hw[::-1], interpolation=cv2.INTER_AREA) for f in full]


def cases() -> dict[str, Callable[[int], object]]:
    """Label -> a function of the render count that renders one frame."""
    plain = GelRenderer(rng=np.random.default_rng(1))
    static = GelRenderer(effects=STATIC_EFFECTS, rng=np.random.default_rng(1))
    blurred = {
        n: GelRenderer(effects=ImageEffects(motion_blur_samples=n), rng=np.random.default_rng(1))
        for n in (2, 3)
    }
    table: dict[str, Callable[[int], object]] = {}
    for name, grid_hw in GRIDS.items():
        fs = fields(grid_hw)
        table[f"no effects | {name}"] = lambda i, fs=fs: plain.render(fs[i % N_FIELDS])
        table[f"noise + drift + blur + dropout + occlusion | {name}"] = lambda i, fs=fs: (
            static.render(fs[i % N_FIELDS], frame_index=i, drift=(i % 50) / 50)
        )
        for n, renderer in blurred.items():
            table[f"motion blur, {n} samples | {name}"] = lambda i, fs=fs, r=renderer: r.render(
                fs[i % N_FIELDS], exposure_start_px=fs[(i + 1) % N_FIELDS]
            )
    return table


def stages() -> dict[str, Callable[[int], object]]:
    """The plain coarse render's stages, each on its own inputs."""
    rng = np.random.default_rng(1)
    centres = marker_lattice(SHAPE_HW, 31.5, 1.5, rng)
    gel = reflectance(speckle(SHAPE_HW, 12.0, rng), marker_coverage(SHAPE_HW, centres, 4.5))
    mapper = BackwardMapper(SHAPE_HW)
    warper = SplineWarper(gel)
    fs = fields(GRIDS["48x64"])
    maps = [mapper(f) for f in fs]
    shading = led_shading(SHAPE_HW)
    return {
        "backward map (48x64 field)": lambda i: mapper(fs[i % N_FIELDS]),
        "warp (half-pixel spline table, cv2.remap)": lambda i: warper(maps[i % N_FIELDS]),
        "shade (LED shading, uint8)": lambda i: shade(warper.image, shading),
    }


def exact() -> dict[str, Callable[[int], object]]:
    renderer = MarkerImageRenderer(rng=np.random.default_rng(1))
    fs = fields(SHAPE_HW)
    return {
        "exact spline (MarkerImageRenderer) | 240x320": lambda i: renderer.render(fs[i % N_FIELDS])
    }


def measure(table: dict[str, Callable[[int], object]], repeats: int) -> dict[str, list[float]]:
    samples: dict[str, list[float]] = {label: [] for label in table}
    for fn in table.values():
        fn(0)  # warm-up: builds the per-resolution tables
    for i in range(repeats):
        for label, fn in table.items():
            began = time.perf_counter()
            fn(i)
            samples[label].append((time.perf_counter() - began) * 1e3)
    return samples


def rows(samples: dict[str, list[float]]) -> list[str]:
    return [
        f"| {label} | {np.median(v):.2f} | {np.percentile(v, 90):.2f} |"
        for label, v in samples.items()
    ]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--repeats", type=integer(1, 1_000_000), default=200, help="renders per case"
    )
    args = parser.parse_args(argv)
    return run_tool("bench_render", lambda: run(args))


def run(args: argparse.Namespace) -> int:
    cv2.setNumThreads(1)
    print(f"GelRenderer, {SHAPE_HW[1]}x{SHAPE_HW[0]} output, median of {args.repeats} renders")
    print()
    print("| case | field grid | median ms | p90 ms |")
    print("|---|---|---:|---:|")
    print("\n".join(rows(measure(cases(), args.repeats))))
    print("\n| stage of the plain 48x64 render | median ms | p90 ms |")
    print("|---|---:|---:|")
    print("\n".join(rows(measure(stages(), args.repeats))))
    slow = max(3, args.repeats // 10)
    print(f"\n| exact renderer, {slow} renders | field grid | median ms | p90 ms |")
    print("|---|---|---:|---:|")
    print("\n".join(rows(measure(exact(), slow))))
    print(f"\nMachine: {describe_machine('1 thread (cv2.setNumThreads(1), OMP/OpenBLAS/MKL 1)')}")
    return 0
