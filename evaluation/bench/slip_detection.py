"""Per-frame cost of the slip detector (controller/tactile/slip.py) on one thread.

Times ``SlipDetector.update`` on the default 16 x 12 grid for a growing, partly slipping
field in two regimes: every frame judged (the field moves by more than the evaluation step
each frame: the worst case) and quiet frames (no evaluation), as median / p90 over many
frames. Also times ``TactileEstimator.push`` on rendered frames with the detector enabled
and disabled.

    python -m evaluation bench_slip [--frames 2000] [--write docs/BENCHMARKS.md]

``--write`` replaces (or appends) the "## Slip detector" section of the file.
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

import cv2
import numpy as np

from controller.cli.outputs import check_output_file, write_text
from controller.cli.support import integer, run_tool
from controller.tactile import TactileEstimator, VectorField, estimator_for_sensor
from controller.tactile.field import grid_axes_mm
from controller.tactile.nhhd import NHHD
from controller.tactile.slip import SlipDetector
from drivers.sim.render.marker_images import MarkerImageRenderer
from evaluation.common.machine_info import describe_machine

SECTION = "## Slip detector"


def _stats_us(samples: list[float]) -> str:
    return f"{np.median(samples) * 1e6:.0f} / {np.percentile(samples, 90) * 1e6:.0f}"


def bench_update(frames: int) -> dict[str, str]:
    config = estimator_for_sensor("gelsight_mini").config.slip
    x_mm, y_mm = grid_axes_mm(320, 240, 16, 12, 0.0634)
    gx, gy = np.meshgrid(x_mm, y_mm)
    core = np.exp(-(gx**2 + gy**2) / (2 * 3.0**2))
    nhhd = NHHD(x_mm, y_mm)
    results = {}
    for label, step_mm in (("every frame judged", 0.05), ("quiet frames", 0.0)):
        detector = SlipDetector(config, x_mm, y_mm)
        samples = []
        for i in range(frames):
            k = i % 200  # a fresh ramp every 200 frames
            u = 0.1 + step_mm * k * (0.5 + core)
            v = 0.3 * u
            field = VectorField(x_mm, y_mm, u, v)
            decomposition = nhhd.decompose(u, v)
            began = time.perf_counter()
            detector.update(field, decomposition, i / 25)
            samples.append(time.perf_counter() - began)
            if k == 199:
                detector.reset()
        results[label] = _stats_us(samples)
    return results


def bench_push(frames: int) -> dict[str, str]:
    base = estimator_for_sensor("gelsight_mini")
    renderer = MarkerImageRenderer(rng=np.random.default_rng(5))
    ys, xs = np.mgrid[0:240, 0:320].astype(np.float32)
    core = np.exp(-((xs - 160) ** 2 + (ys - 120) ** 2) / (2 * 60.0**2))
    images = []
    for k in range(12):
        field = np.zeros((240, 320, 2), np.float32)
        field[..., 0] = 0.8 * k * (0.5 + core)
        images.append(renderer.render(field))
    results = {}
    for label, enabled in (("push, detector on", True), ("push, detector off", False)):
        slip = replace(base.config.slip, enabled=enabled)
        est = TactileEstimator(replace(base.config, slip=slip), base.profile)
        est.set_reference(renderer.render())
        samples = []
        for i in range(frames):
            began = time.perf_counter()
            est.push(images[i % len(images)], i / 25)
            samples.append(time.perf_counter() - began)
        results[label] = f"{np.median(samples) * 1e3:.2f} / {np.percentile(samples, 90) * 1e3:.2f}"
    return results


def report(update: dict[str, str], push: dict[str, str], frames: int) -> str:
    machine = describe_machine("1 thread (cv2.setNumThreads(1))")
    lines = [
        SECTION,
        "",
        "Regenerate with `python -m evaluation bench_slip --write docs/BENCHMARKS.md`. "
        f"Machine: {machine}. {frames} frames per detector case (a tenth of that per push "
        "case); the detector's budget is 0.2 ms per frame.",
        "",
        "| case | median / p90 |",
        "|---|---|",
    ]
    lines += [f"| `SlipDetector.update`, {k} | {v} µs |" for k, v in update.items()]
    lines += [f"| `TactileEstimator.push`, {k.split(', ')[1]} | {v} ms |" for k, v in push.items()]
    return "\n".join(lines) + "\n"


def write_section(path: Path, section: str) -> None:
    """Replace (or append) this script's section of the markdown file at ``path``."""
    previous = path.read_text() if path.exists() else "# Benchmarks\n"
    if SECTION in previous:
        head, rest = previous.split(SECTION, 1)
        tail = rest.split("\n## ", 1)[1] if "\n## " in rest else None
        text = head + section + ("\n## " + tail if tail is not None else "")
    else:
        text = previous.rstrip("\n") + "\n\n" + section
    write_text(path, text)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--frames",
        type=integer(10, 1_000_000),
        default=2000,
        help="frames per detector case (a tenth per push case)",
    )
    parser.add_argument("--write", type=Path, help="update this markdown file's section")
    args = parser.parse_args(argv)
    return run_tool("bench_slip", lambda: run(args))


def run(args: argparse.Namespace) -> int:
    if args.write:
        check_output_file(args.write, option="--write")
    cv2.setNumThreads(1)
    text = report(bench_update(args.frames), bench_push(args.frames // 10), args.frames)
    sys.stdout.write(text)
    if args.write:
        write_section(args.write, text)
    return 0
