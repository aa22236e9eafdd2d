"""Offline estimation on recorded tactile video or a folder of images.

    python scripts/estimate.py INPUT --reference SPEC --out OUT.csv [--sensor gelsight_mini]
        [--method NAME] [--calibration FILE] [--fps F]

INPUT is a video file OpenCV can read, or a folder of images read in natural sorted order
(frame_2 before frame_10). SPEC is a frame index (``0``) or a range ``a:b`` whose frames
(a included, b excluded) are averaged into the zeroing reference. ``--method`` names an
estimator configuration (configs/estimators/NAME.yaml) or is a path to one; without it the
sensor profile's ``estimator`` is used.

The CSV has one row per frame: ``frame,time_s,tau_x,tau_y,tau_z,shear_x,shear_y,normal,
fv_tau_x,fv_tau_y,fv_tau_z,contact,degenerate,slip_suspected,slip_gross,rezero_recommended,
latency_ms``. Without a calibration file the values are raw (mm, mm^2; see
controller/tactile/wrench.py); the flags are 0 or 1; ``latency_ms`` is the estimator's time
for that frame.

Expected failures (unreadable input, empty folder, mismatched frame sizes, reference out of
range, bad configuration) print one line ``estimate: error: ...`` and exit with code 2.
"""

from __future__ import annotations

import argparse
import csv
import re
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
from tqdm import tqdm

from controller.tactile.calibration import Calibration
from controller.tactile.estimator import TactileEstimator
from controller.tactile.settings import sensor_estimator
from controller.tactile.wrench import VALUE_FIELDS, WrenchEstimate
from drivers.config import ConfigError
from drivers.tactile.profile import sensor_profile

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff")
FLAG_FIELDS = ("contact", "degenerate", "slip_suspected", "slip_gross", "rezero_recommended")
CSV_COLUMNS = ("frame", "time_s", *VALUE_FIELDS, *FLAG_FIELDS, "latency_ms")
PROGRESS_MIN_FRAMES = 100


class InputError(Exception):
    """A user-facing problem with the input; the message is one line."""


def _natural_key(path: Path) -> list[object]:
    return [int(part) if part.isdigit() else part.lower() for part in re.split(r"(\d+)", path.name)]


@dataclass
class FrameSource:
    """Frames of a video file or an image folder, read in order."""

    path: Path
    images: list[Path] | None  # None for a video
    frame_count: int | None
    fps: float | None

    def frames(self) -> Iterator[np.ndarray]:
        if self.images is not None:
            for image_path in self.images:
                image = cv2.imread(str(image_path), cv2.IMREAD_COLOR)
                if image is None:
                    raise InputError(f"cannot read image '{image_path}'")
                yield image
            return
        capture = cv2.VideoCapture(str(self.path))
        try:
            while True:
                ok, frame = capture.read()
                if not ok:
                    return
                yield frame
        finally:
            capture.release()


def open_source(path: Path) -> FrameSource:
    """Open INPUT, checking that it exists and holds at least one readable frame."""
    if not path.exists():
        raise InputError(f"input '{path}' does not exist")
    if path.is_dir():
        images = sorted(
            (p for p in path.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES), key=_natural_key
        )
        if not images:
            suffixes = ", ".join(IMAGE_SUFFIXES)
            raise InputError(f"folder '{path}' holds no images ({suffixes})")
        return FrameSource(path, images, len(images), None)
    capture = cv2.VideoCapture(str(path))
    try:
        ok = capture.isOpened() and capture.read()[0]
        count = int(capture.get(cv2.CAP_PROP_FRAME_COUNT)) if ok else 0
        fps = float(capture.get(cv2.CAP_PROP_FPS)) if ok else 0.0
    finally:
        capture.release()
    if not ok:
        raise InputError(f"cannot read video '{path}': OpenCV cannot open or decode it")
    return FrameSource(path, None, count if count > 0 else None, fps if fps > 0 else None)


def parse_reference(spec: str) -> tuple[int, int]:
    """``'5'`` -> (5, 6); ``'a:b'`` -> (a, b). Raises InputError on anything else."""
    match = re.fullmatch(r"\s*(\d+)\s*(?::\s*(\d+)\s*)?", spec)
    if not match:
        raise InputError(f"--reference '{spec}': expected a frame index N or a range A:B")
    start = int(match.group(1))
    stop = int(match.group(2)) if match.group(2) is not None else start + 1
    if stop <= start:
        raise InputError(f"--reference '{spec}': the range A:B needs B > A")
    return start, stop


def read_reference(source: FrameSource, start: int, stop: int) -> list[np.ndarray]:
    """The frames [start, stop) of the source."""
    if source.frame_count is not None and stop > source.frame_count:
        raise InputError(
            f"--reference {start}:{stop} is out of range: '{source.path}' has "
            f"{source.frame_count} frames"
        )
    frames = []
    for index, frame in enumerate(source.frames()):
        if index >= start:
            frames.append(frame)
        if index + 1 >= stop:
            break
    if len(frames) < stop - start:
        raise InputError(
            f"--reference {start}:{stop} is out of range: '{source.path}' ended after "
            f"{start + len(frames)} frames"
        )
    return frames


def _row(index: int, t_s: float, estimate: WrenchEstimate, latency_ms: float) -> list[object]:
    values = (f"{getattr(estimate, name):.9g}" for name in VALUE_FIELDS)
    flags = (int(getattr(estimate, name)) for name in FLAG_FIELDS)
    return [index, f"{t_s:.6f}", *values, *flags, f"{latency_ms:.3f}"]


def estimate_file(
    input_path: Path,
    out_csv: Path,
    reference: str = "0",
    sensor: str = "gelsight_mini",
    method: str | None = None,
    calibration: Path | None = None,
    fps: float | None = None,
) -> int:
    """Run the estimator over INPUT and write the CSV; returns the number of frames."""
    start, stop = parse_reference(reference)
    if fps is not None and not fps > 0:
        raise InputError(f"--fps {fps}: expected a positive number of frames per second")
    profile = sensor_profile(sensor)
    _, config = sensor_estimator(profile, method)
    fit = Calibration.load(calibration) if calibration is not None else None
    source = open_source(input_path)
    rate_hz = fps or source.fps or profile.fps_hz

    estimator = TactileEstimator(config, profile, fit)
    reference_frames = read_reference(source, start, stop)
    try:
        estimator.set_reference(reference_frames)
    except ValueError as exc:
        raise InputError(f"reference frames {start}:{stop}: {exc}") from None

    show_progress = source.frame_count is None or source.frame_count >= PROGRESS_MIN_FRAMES
    count = 0
    try:
        out_csv.parent.mkdir(parents=True, exist_ok=True)
        handle = out_csv.open("w", newline="")
    except OSError as exc:
        raise InputError(f"cannot write '{out_csv}': {exc.strerror}") from None
    with handle:
        writer = csv.writer(handle)
        writer.writerow(CSV_COLUMNS)
        frames = tqdm(
            source.frames(),
            total=source.frame_count,
            unit="frame",
            disable=not show_progress,
            file=sys.stderr,
            leave=False,
        )
        for index, frame in enumerate(frames):
            t_s = index / rate_hz
            began = time.perf_counter()
            try:
                estimate = estimator.push(frame, t_s)
            except ValueError as exc:
                raise InputError(f"frame {index}: {exc}") from None
            latency_ms = (time.perf_counter() - began) * 1e3
            writer.writerow(_row(index, t_s, estimate, latency_ms))
            count += 1
    return count


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="estimate",
        description="Estimate in-grasp torques from recorded visuotactile frames.",
    )
    parser.add_argument("input", type=Path, help="video file, or folder of images")
    parser.add_argument(
        "--reference",
        default="0",
        help="zeroing reference: frame index N, or range A:B averaged (default 0)",
    )
    parser.add_argument("--out", type=Path, required=True, help="output CSV path")
    parser.add_argument(
        "--sensor",
        default="gelsight_mini",
        help="sensor profile name (configs/sensors) or YAML path",
    )
    parser.add_argument(
        "--method",
        default=None,
        help="estimator configuration name (configs/estimators) or YAML path "
        "(default: the sensor profile's estimator)",
    )
    parser.add_argument(
        "--calibration", type=Path, default=None, help="calibration YAML from scripts/calibrate.py"
    )
    parser.add_argument(
        "--fps",
        type=float,
        default=None,
        help="frame rate for time_s (default: the video's, else the sensor's)",
    )
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        count = estimate_file(
            args.input,
            args.out,
            args.reference,
            args.sensor,
            args.method,
            args.calibration,
            args.fps,
        )
    except (InputError, ConfigError) as exc:
        print(f"estimate: error: {exc}", file=sys.stderr)
        return 2
    print(f"estimate: wrote {count} rows to {args.out}")
    return 0
