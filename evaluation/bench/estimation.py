"""Speed and field accuracy of every estimator configuration, at 320 x 240 on one thread.

For each configuration: median and p90 latency of each stage (flow, pooling, the divergence
the dipole sees (with its pooling and curl-free part),
dipole, NHHD, FingerVision baseline) and of the whole pipeline (``TactileEstimator.push``),
paired with the grid field error (px RMSE) against the known area-mean displacement of
sub-pixel warps of a rendered marker-gel image. Two families of warps: "smooth" (Gaussian
bumps 40-120 px wide, like a broad press) and "contact" (15-40 px wide, like the edge of a
peg's contact patch), each at peak displacements 0.1, 0.5, 1, 2 and 3 px.

    python -m evaluation bench_estimation [--write docs/BENCHMARKS.md] [--repeats 5] [--quick]
    (``make bench``)
"""

from __future__ import annotations

import argparse
import time
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from controller.cli.outputs import check_output_file, write_text
from controller.cli.support import integer, run_tool
from controller.tactile import EstimatorConfig, TactileEstimator
from controller.tactile.flow import DenseGridFlow, GridFlow, make_grid_flow
from controller.tactile.grid_pipeline import GridPipeline
from core.sensor_profile import sensor_profile
from drivers.sim.render.marker_images import MarkerImageRenderer, area_mean_field
from evaluation.common.machine_info import describe_machine
from evaluation.experiments.configurations import estimator_variants

AMPLITUDES_PX = (0.1, 0.5, 1.0, 2.0, 3.0)
FAMILIES = {"smooth": (40.0, 120.0), "contact": (15.0, 40.0)}
SHAPE_HW = (240, 320)


def bump_field(
    rng: np.random.Generator, amplitude: float, widths: tuple[float, float]
) -> np.ndarray:
    """A forward field (H, W, 2) px: four Gaussian bumps of random direction and the given
    width range, scaled to the peak ``amplitude``."""
    height, width = SHAPE_HW
    ys, xs = np.mgrid[0:height, 0:width].astype(np.float64)
    field = np.zeros((height, width, 2))
    for _ in range(4):
        cx, cy, sigma = rng.uniform(0, width), rng.uniform(0, height), rng.uniform(*widths)
        bump = np.exp(-((xs - cx) ** 2 + (ys - cy) ** 2) / (2 * sigma**2))
        field[..., 0] += rng.normal() * bump
        field[..., 1] += rng.normal() * bump
    return (field * amplitude / np.hypot(field[..., 0], field[..., 1]).max()).astype(np.float32)


@dataclass
class Case:
    family: str
    image: np.ndarray
    field: np.ndarray  # dense forward field, px


def make_cases(per_amplitude: int, seed: int = 2024) -> tuple[np.ndarray, list[Case]]:
    rng = np.random.default_rng(seed)
    renderer = MarkerImageRenderer(rng=rng)
    cases = [
        Case(family, renderer.render(field), field)
        for family, widths in FAMILIES.items()
        for amplitude in AMPLITUDES_PX
        for _ in range(per_amplitude)
        for field in [bump_field(rng, amplitude, widths)]
    ]
    return renderer.render(), cases


def timed(fn, *args) -> float:
    began = time.perf_counter()
    fn(*args)
    return (time.perf_counter() - began) * 1e3


def stats(samples: list[float]) -> tuple[float, float]:
    return float(np.median(samples)), float(np.percentile(samples, 90))


def bench(config: EstimatorConfig, reference: np.ndarray, cases: list[Case], repeats: int) -> dict:
    profile = sensor_profile("gelsight_mini")
    flows: list[GridFlow] = []

    def keep_flow(*args) -> GridFlow:
        flows.append(make_grid_flow(*args))
        return flows[-1]

    est = TactileEstimator(config, profile, flow=keep_flow)
    est.set_reference(reference)
    flow = flows[-1]  # the estimator's own; the stages are timed one by one below
    field = est.field
    rows, cols = field.shape
    stages = GridPipeline(config, profile.mm_per_px, field.x_mm, field.y_mm)
    grid = np.empty((rows, cols, 2))
    u, v = np.empty((rows, cols)), np.empty((rows, cols))
    times: dict[str, list[float]] = {
        k: [] for k in ("flow", "pool", "div", "dipole", "nhhd", "baseline", "push")
    }
    errors: dict[str, list[float]] = {family: [] for family in FAMILIES}
    for case in cases:
        flow.measure(case.image, grid)
        truth = area_mean_field(case.field, rows, cols)
        errors[case.family].append(float(np.sqrt(((grid - truth) ** 2).sum(-1).mean())))
    for repeat in range(repeats):
        for i, case in enumerate(cases):
            if isinstance(flow, DenseGridFlow):
                began = time.perf_counter()
                dense = flow.dense(case.image)
                times["flow"].append((time.perf_counter() - began) * 1e3)
                times["pool"].append(timed(flow.pool, dense, grid))
            else:
                times["flow"].append(timed(flow.measure, case.image, grid))
            np.multiply(grid[..., 0], profile.mm_per_px, out=u)
            np.multiply(grid[..., 1], profile.mm_per_px, out=v)
            times["nhhd"].append(timed(stages.nhhd.decompose, u, v))
            decomposition = stages.nhhd.decompose(u, v)
            times["div"].append(timed(stages.divergence, u, v, decomposition))
            times["dipole"].append(timed(stages.dipole, stages.divergence(u, v, decomposition)))
            times["baseline"].append(timed(stages.baseline, u, v))
            t_s = float(repeat * len(cases) + i)  # frame times never go backwards
            times["push"].append(timed(est.push, case.image, t_s))
    return {
        "grid": f"{cols}x{rows}",
        "times": {k: stats(v) for k, v in times.items() if v},
        "errors": {k: float(np.sqrt(np.mean(np.square(v)))) for k, v in errors.items()},
        "error_all": float(np.sqrt(np.mean(np.square(sum(errors.values(), []))))),
        "per_amplitude": errors,
    }


def fmt(t: tuple[float, float], unit: float = 1.0, digits: int = 2) -> str:
    return f"{t[0] * unit:.{digits}f} / {t[1] * unit:.{digits}f}"


def table(results: list[tuple[str, dict]]) -> str:
    lines = [
        "| configuration | grid | flow ms | pool ms | tilt div µs | dipole µs | NHHD µs | FV µs "
        "| **pipeline ms** | err smooth px | err contact px | **err all px** |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for label, r in results:
        t = r["times"]
        pool = fmt(t["pool"]) if "pool" in t else "(in flow)"
        lines.append(
            f"| {label} | {r['grid']} | {fmt(t['flow'])} | {pool} | {fmt(t['div'], 1e3, 0)} "
            f"| {fmt(t['dipole'], 1e3, 0)} | {fmt(t['nhhd'], 1e3, 0)} "
            f"| {fmt(t['baseline'], 1e3, 0)} "
            f"| **{fmt(t['push'])}** | {r['errors']['smooth']:.4f} | {r['errors']['contact']:.4f} "
            f"| **{r['error_all']:.4f}** |"
        )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", type=Path, help="write the report (markdown) to this file")
    parser.add_argument(
        "--repeats", type=integer(1, 10_000), default=5, help="timing passes over the warps"
    )
    parser.add_argument(
        "--quick", action="store_true", help="two configurations, one warp each, two passes"
    )
    args = parser.parse_args(argv)
    return run_tool("bench_estimation", lambda: run(args))


def run(args: argparse.Namespace) -> int:
    if args.write:
        check_output_file(args.write, option="--write")
    cv2.setNumThreads(1)
    reference, cases = make_cases(per_amplitude=1 if args.quick else 3)
    results = []
    for label, config in estimator_variants(args.quick):
        results.append((label, bench(config, reference, cases, 2 if args.quick else args.repeats)))
        t = results[-1][1]
        print(
            f"{label:50s} pipeline {fmt(t['times']['push'])} ms  err {t['error_all']:.4f} px",
            flush=True,
        )
    report = "\n".join(
        [
            "# Benchmarks",
            "",
            "## Estimation pipeline: latency and field error",
            "",
            "Regenerate with `make bench` (`python -m evaluation bench_estimation --write "
            "docs/BENCHMARKS.md`).",
            "",
            f"Machine: {describe_machine('1 thread (cv2.setNumThreads(1))')}.",
            "",
            f"Latency: median / p90 in ms (µs for the grid operators) per 320x240 frame, over "
            f"{len(cases)} warps x {args.repeats if not args.quick else 1} passes. Field error: "
            f"RMSE in px of the grid displacement against the area mean of the true warp over "
            f"each cell, for {len(cases) // 2} smooth and {len(cases) // 2} contact-like warps "
            f"with peak displacements {', '.join(str(a) for a in AMPLITUDES_PX)} px. The "
            "pipeline column is "
            "`TactileEstimator.push` (frame to wrench estimate: flow, pooling, NHHD, dipole, "
            "baseline); stage columns are timed separately.",
            "",
            table(results),
            "",
        ]
    )
    print(report)
    if args.write:
        previous = args.write.read_text() if args.write.exists() else ""
        marker = "\n## "
        tail = ""
        if "## Estimation pipeline" in previous:
            rest = previous.split("## Estimation pipeline", 1)[1]
            if marker in rest:
                tail = marker + rest.split(marker, 1)[1]
        elif previous.startswith("# Benchmarks"):
            tail = "\n" + previous.split("\n", 1)[1]
        write_text(args.write, report + tail)
        print(f"wrote {args.write}")
    return 0
