"""Benchmark: GelSight Mini frame (3280 x 2464 MJPG) to the 320 x 240 image, full vs reduced decode.

For synthetic Mini-like JPEGs (a marker grid on shaded gel plus sensor noise) at several
qualities, time on one thread (cv2.setNumThreads(1)):

* full: cv2.imdecode at full size, crop 15 % per border, INTER_AREA resize to 320 x 240;
* /2, /4, /8: the same after decoding at reduced size (libjpeg DCT scaling,
  cv2.IMREAD_REDUCED_COLOR_2/4/8), the driver's path for MJPG buffers.

Prints a markdown table of median and p90 milliseconds per frame and the mean absolute
difference (uint8 levels) of each reduced output against the full-decode output, then the
machine. Run: ``.venv/bin/python -m evaluation bench_camera_decode [--runs 40]``.
"""

from __future__ import annotations

import argparse
import time

import cv2
import numpy as np

from controller.cli.support import SEED, integer, run_tool
from drivers.tactile.decode import FrameProcessor, decode_jpeg
from evaluation.common.machine_info import describe_machine

WIDTH_PX, HEIGHT_PX = 3280, 2464
QUALITIES = (70, 85, 95)
DOWNSCALES = (1, 2, 4, 8)


def mini_like_frame(rng: np.random.Generator) -> np.ndarray:
    """A 3280 x 2464 BGR frame: lit gel gradient, dark marker dots every ~1 mm, a pressed
    blob, Gaussian sensor noise (sigma 3 levels)."""
    yy, xx = np.mgrid[0:HEIGHT_PX, 0:WIDTH_PX].astype(np.float32)
    gel = np.stack(
        [110 + 40 * xx / WIDTH_PX, 120 + 30 * yy / HEIGHT_PX, 140 - 30 * xx / WIDTH_PX], axis=2
    )
    cx, cy, r = 0.55 * WIDTH_PX, 0.45 * HEIGHT_PX, 0.12 * WIDTH_PX
    press = np.exp(-((xx - cx) ** 2 + (yy - cy) ** 2) / (2 * r * r))[..., None]
    image = np.clip(gel + 60 * press * np.array([0.2, 1.0, 0.6]), 0, 255).astype(np.uint8)
    pitch = 110  # px between markers
    for y in range(pitch // 2, HEIGHT_PX, pitch):
        for x in range(pitch // 2, WIDTH_PX, pitch):
            cv2.circle(image, (x, y), 14, (25, 25, 30), -1, lineType=cv2.LINE_AA)
    noise = rng.normal(0.0, 3.0, image.shape)
    return np.clip(image + noise, 0, 255).astype(np.uint8)


def process(jpeg: np.ndarray, downscale: int) -> np.ndarray:
    processor = FrameProcessor(320, 240, crop_border_fraction=0.15, jpeg_downscale=downscale)
    return processor.process_decoded(decode_jpeg(jpeg, downscale))


def time_ms(jpeg: np.ndarray, downscale: int, runs: int) -> tuple[float, float]:
    samples = []
    process(jpeg, downscale)  # warm-up
    for _ in range(runs):
        t0 = time.perf_counter()
        process(jpeg, downscale)
        samples.append((time.perf_counter() - t0) * 1e3)
    return float(np.median(samples)), float(np.percentile(samples, 90))


def jpeg_library() -> str:
    """The JPEG library OpenCV was built with (its build information's "JPEG:" line)."""
    return next(
        (
            line.split(":", 1)[1].strip()
            for line in cv2.getBuildInformation().splitlines()
            if line.strip().startswith("JPEG:")
        ),
        "?",
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=integer(1, 100_000), default=40, help="timed runs per cell")
    parser.add_argument("--seed", type=SEED, default=0)
    args = parser.parse_args(argv)
    return run_tool("bench_camera_decode", lambda: bench(args))


def bench(args: argparse.Namespace) -> int:
    cv2.setNumThreads(1)
    frame = mini_like_frame(np.random.default_rng(args.seed))
    print(
        f"{WIDTH_PX}x{HEIGHT_PX} synthetic Mini frame -> crop 15 % -> 320x240, {args.runs} runs\n"
    )
    print("| JPEG quality | size (kB) | decode | median (ms) | p90 (ms) | mean abs diff vs full |")
    print("|---:|---:|---|---:|---:|---:|")
    for quality in QUALITIES:
        ok, jpeg = cv2.imencode(".jpg", frame, [cv2.IMWRITE_JPEG_QUALITY, quality])
        assert ok
        jpeg = jpeg.reshape(1, -1)  # the layout V4L2 hands over with CONVERT_RGB off
        reference = process(jpeg, 1).astype(np.int16)
        for downscale in DOWNSCALES:
            median, p90 = time_ms(jpeg, downscale, args.runs)
            diff = float(np.abs(process(jpeg, downscale) - reference).mean())
            label = "full" if downscale == 1 else f"1/{downscale}"
            print(
                f"| {quality} | {jpeg.size / 1e3:.0f} | {label} | {median:.1f} | {p90:.1f} "
                f"| {diff:.2f} |"
            )
    print(f"\nMachine: {describe_machine(f'1 OpenCV thread, JPEG: {jpeg_library()}')}")
    return 0
