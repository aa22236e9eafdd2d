"""Offline estimation on recorded tactile video or a folder of images.

    tactile estimate INPUT [IMAGE ...] --reference SPEC --out OUT.csv
        [--sensor gelsight_mini] [--method NAME] [--open SPEC] [--calibration FILE [--force]]
        [--fps F] [--allow-damaged]

INPUT is a video file OpenCV can read, a folder of images read in natural sorted order
(frame_2 before frame_10), or one or more image files read in the order given (still
captures: ``shot_rest.png shot_pressed.png``). All frames must have one size (one sensor's
images; either orientation). SPEC is a frame number (``0``) or a range ``a:b`` whose frames
(a included, b excluded) are averaged into the zeroing reference. ``--open`` names frames
of the open gel (before the grasp, nothing touching), in the same form: the
``grasp_centroid`` dipole origin takes the contact's centre from the reference against them
(without, the tool finds the contact's support from the whole recording, each cell's
divergence power against its frame-to-frame noise (controller/offline/recording_support.py),
estimates the recording again about it, or on the whole grid through the paper's EMA when no
cell's divergence varies clearly more than the noise alone would, behind the no-contact gate
unless that gate never saw a press from the open gel (the recording was zeroed in the grasp),
says so in one line and records the choice in ``OUT.fallback.json``). The open frames must
end before the reference begins (overlapping or later ranges are refused); open frames that
differ from each other or from the recording's first frame far beyond the camera noise are
used with one warning (controller/offline/open_gel.py). ``--method`` names an estimator
configuration (configs/estimators/NAME.yaml) or is a path to one; without it the
sensor profile's ``estimator`` is used. A calibration file fitted for another sensor or
estimator configuration is refused unless ``--force``.

The CSV has one row per frame: ``frame,time_s,tau_x,tau_y,tau_z,shear_x,shear_y,normal,
fv_tau_x,fv_tau_y,fv_tau_z,contact,degenerate,slip_suspected,slip_gross,rezero_recommended,
latency_ms``. ``frame`` is the frame's number in the recording (by the container's
timestamps for a video, the position in the sorted folder or the list of images) and
``time_s = frame / rate`` (``--fps``, else the video's rate, else the sensor's), so a lost
frame leaves a gap and every time stays true. Without a calibration file the values are
raw (mm, mm^2; see controller/tactile/wrench.py); the flags are 0 or 1; ``latency_ms`` is
the estimator's time for that frame.

Damaged input (frames that do not decode, a video that ends before the frame count in its
header) is an error by default; with ``--allow-damaged`` the frames that decode are
estimated and each kind of loss is one ``estimate: warning: ...`` line. The CSV is written
to a temporary file and renamed over OUT only when complete: an error or an interruption
leaves an earlier OUT as it was. Expected failures (unreadable input, empty folder,
mismatched frame sizes (naming the image), several inputs that are not all image files,
reference out of range, bad configuration, an OUT that is an input
or cannot be written) print one line ``estimate: error: ...`` and exit with code 2; SIGINT
and SIGTERM exit with 130 and 143 (controller/cli/support.py).
"""

from __future__ import annotations

import argparse
import csv
import json
import re
import sys
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TextIO

import numpy as np
from tqdm import tqdm

from controller.cli.outputs import atomic_text, check_output_file
from controller.cli.support import (
    ToolError,
    resolved_config_path,
    run_tool,
)
from controller.offline.open_gel import open_gel_doubt
from controller.offline.quiet_decoding import read_image
from controller.offline.recording_support import recording_fallback, uses_recording
from controller.offline.video import ReadLog, VideoError, VideoFile
from controller.tactile import (
    Calibration,
    EstimatorConfig,
    TactileEstimator,
    WrenchEstimate,
    estimator_for_sensor,
)
from controller.tactile.wrench import VALUE_FIELDS
from core.sensor_profile import sensor_profile
from core.subcommands import job_prog

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff")
FLAG_FIELDS = ("contact", "degenerate", "slip_suspected", "slip_gross", "rezero_recommended")
CSV_COLUMNS = ("frame", "time_s", *VALUE_FIELDS, *FLAG_FIELDS, "latency_ms")
PROGRESS_MIN_FRAMES = 100
MIN_RATE_HZ, MAX_RATE_HZ = 0.1, 10_000.0


class InputError(ToolError):
    """A user-facing problem with the input; the message is one line."""


def _natural_key(path: Path) -> list[object]:
    return [int(part) if part.isdigit() else part.lower() for part in re.split(r"(\d+)", path.name)]


def _warn(message: str) -> None:
    print(f"estimate: warning: {message}", file=sys.stderr)


@dataclass
class FrameSource:
    """Frames of a video file, an image folder or a list of images, read in order and
    numbered (see the module doc); ``frame_count`` and ``fps`` come from the video's header
    (None: unknown)."""

    path: Path
    images: list[Path] | None  # None for a video
    video: VideoFile | None
    frame_count: int | None = field(init=False)
    fps: float | None = field(init=False)

    def __post_init__(self) -> None:
        if self.images is not None:
            self.frame_count, self.fps = len(self.images), None
        else:
            assert self.video is not None
            self.frame_count, self.fps = self.video.header_frames, self.video.fps

    def describe(self, number: int) -> str:
        """``frame N``, with the image's file name for images."""
        if self.images is None or not 0 <= number < len(self.images):
            return f"frame {number}"
        return f"frame {number} ({self.images[number].name})"

    def frames(self, log: ReadLog) -> Iterator[tuple[int, np.ndarray]]:
        """(frame number, image) of every frame that decodes; ``log`` records the pass."""
        if self.video is not None:
            yield from self.video.frames(log)
            return
        for number, image_path in enumerate(self.images or ()):
            image = read_image(image_path)
            if image is not None:
                log.record(number)
                yield number, image

    def damage(self, log: ReadLog) -> list[str]:
        """What a complete pass logged in ``log`` lost; empty for an intact input."""
        if self.video is not None:
            return [f"'{self.path}': {problem}" for problem in log.damage(self.frame_count)]
        images = self.images or []
        missing = [n for first, last in log.gaps for n in range(first, last + 1)]
        bad = [images[n].name for n in [*missing, *range(log.last + 1, len(images))]]
        if not bad:
            return []
        names = ", ".join(bad[:5]) + (f" and {len(bad) - 5} more" if len(bad) > 5 else "")
        return [f"'{self.path}': {len(bad)} images did not decode ({names})"]


def open_images(paths: list[Path]) -> FrameSource:
    """A list of image files, in the order given, read as one recording."""
    for path in paths:
        if not path.exists():
            raise InputError(f"input '{path}' does not exist")
        if not path.is_file() or path.suffix.lower() not in IMAGE_SUFFIXES:
            raise InputError(
                f"input '{path}': with several inputs, expected image files only "
                f"({', '.join(IMAGE_SUFFIXES)}); give one video or one folder on its own"
            )
    return FrameSource(paths[0] if len(paths) == 1 else paths[0].parent, list(paths), None)


def open_source(path: Path | Sequence[Path]) -> FrameSource:
    """Open INPUT (one path, or several image files), checking that it exists and holds at
    least one readable frame."""
    if not isinstance(path, Path):
        paths = list(path)
        if len(paths) != 1:
            return open_images(paths)
        path = paths[0]
    if path.is_file() and path.suffix.lower() in IMAGE_SUFFIXES:
        return open_images([path])
    if not path.exists():
        raise InputError(f"input '{path}' does not exist")
    if path.is_dir():
        images = sorted(
            (p for p in path.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES and p.is_file()),
            key=_natural_key,
        )
        if not images:
            suffixes = ", ".join(IMAGE_SUFFIXES)
            raise InputError(f"folder '{path}' holds no images ({suffixes})")
        return FrameSource(path, images, None)
    if not path.is_file():
        raise InputError(f"input '{path}' is not a regular file or a folder")
    try:
        return FrameSource(path, None, VideoFile.open(path))
    except VideoError as exc:
        raise InputError(str(exc)) from None


def parse_reference(spec: str, option: str = "--reference") -> tuple[int, int]:
    """``'5'`` -> (5, 6); ``'a:b'`` -> (a, b). Raises InputError, naming ``option``, on
    anything else."""
    match = re.fullmatch(r"\s*(\d+)\s*(?::\s*(\d+)\s*)?", spec)
    if not match:
        raise InputError(f"{option} '{spec}': expected a frame index N or a range A:B")
    start = int(match.group(1))
    stop = int(match.group(2)) if match.group(2) is not None else start + 1
    if stop <= start:
        raise InputError(f"{option} '{spec}': the range A:B needs B > A")
    return start, stop


def check_open_before_reference(open_range: tuple[int, int], reference: tuple[int, int]) -> None:
    """InputError unless the open gel's frames all come before the reference's: the open gel
    is seen before the grasp, the reference after it."""
    (a, b), (c, d) = open_range, reference
    if b <= c:
        return
    if a < d:
        problem = f"--open {a}:{b} and --reference {c}:{d} overlap"
    else:
        problem = f"--open {a}:{b} comes after --reference {c}:{d}"
    raise InputError(
        f"{problem}: the open gel (before the grasp, nothing touching) must end before the "
        "reference (the grasp, zeroed) begins"
    )


def read_reference(
    source: FrameSource, start: int, stop: int, option: str = "--reference"
) -> list[np.ndarray]:
    """The frames numbered [start, stop) of the source; every one must have decoded."""
    frames = []
    log = ReadLog()
    for number, frame in source.frames(log):
        if number >= stop:
            break
        if number >= start:
            frames.append(frame)
    else:
        if log.last < stop - 1:
            header = (
                f" (its header says {source.frame_count})"
                if source.video is not None and source.frame_count != log.read
                else ""
            )
            raise InputError(
                f"{option} {start}:{stop} is out of range: '{source.path}' ended after "
                f"{log.read} frames{header}"
            )
    if len(frames) < stop - start:
        raise InputError(
            f"{option} {start}:{stop}: {stop - start - len(frames)} of these frames of "
            f"'{source.path}' are missing or did not decode; choose another range"
        )
    return frames


def csv_row(index: int, t_s: float, estimate: WrenchEstimate, latency_ms: float) -> list[object]:
    values = (f"{getattr(estimate, name):.9g}" for name in VALUE_FIELDS)
    flags = (int(getattr(estimate, name)) for name in FLAG_FIELDS)
    return [index, f"{t_s:.6f}", *values, *flags, f"{latency_ms:.3f}"]


def load_calibration(
    path: Path, sensor: str, config: EstimatorConfig, force: bool, warn: Callable[[str], None]
) -> Calibration:
    """The calibration at ``path``, refused if fitted for another sensor or estimator
    configuration (a warning instead with ``force``)."""
    calibration = Calibration.load(path)
    problem = calibration.mismatch(sensor, config)
    if problem and not force:
        raise InputError(
            f"--calibration '{path}' does not fit: {problem}; pass --force to apply it anyway"
        )
    if problem:
        warn(f"--calibration '{path}': {problem}; applied anyway (--force)")
    return calibration


def fallback_sidecar(out_csv: Path) -> Path:
    """Where the tool records a configuration it chose by itself for ``out_csv``."""
    return out_csv.with_name(out_csv.stem + ".fallback.json")


def _write_rows(
    estimator: TactileEstimator,
    source: FrameSource,
    rate_hz: float,
    handle: TextIO,
    divergences: list[np.ndarray] | None = None,
) -> tuple[int, list[str]]:
    """Write the CSV (header and a row per frame that decodes) of ``source`` to ``handle``;
    returns the rows written and what the pass lost. ``divergences``: if given, each frame's
    ``field_divergence`` is appended to it."""
    show_progress = source.frame_count is None or source.frame_count >= PROGRESS_MIN_FRAMES
    log = ReadLog()
    writer = csv.writer(handle)
    writer.writerow(CSV_COLUMNS)
    count = 0
    frames = tqdm(
        source.frames(log),
        total=source.frame_count,
        unit="frame",
        disable=not show_progress,
        file=sys.stderr,
        leave=False,
    )
    for number, frame in frames:
        t_s = number / rate_hz
        began = time.perf_counter()
        try:
            estimate = estimator.push(frame, t_s)
        except ValueError as exc:
            hint = (
                "; a recording's frames share one size: give the images of one sensor"
                if source.images is not None and "does not match" in str(exc)
                else ""
            )
            raise InputError(f"{source.describe(number)}: {exc}{hint}; nothing written") from None
        latency_ms = (time.perf_counter() - began) * 1e3
        writer.writerow(csv_row(number, t_s, estimate, latency_ms))
        if divergences is not None:
            divergences.append(estimator.field_divergence())
        count += 1
    return count, source.damage(log)


def estimate_file(
    input_path: Path | Sequence[Path],
    out_csv: Path,
    reference: str = "0",
    sensor: str = "gelsight_mini",
    method: str | None = None,
    calibration: Path | None = None,
    fps: float | None = None,
    force: bool = False,
    allow_damaged: bool = False,
    warn: Callable[[str], None] = _warn,
    open_gel: str | None = None,
) -> int:
    """Run the estimator over INPUT (a video or folder path, or image file paths) and write
    the CSV; returns the number of rows. Every argument and the output path are checked
    before any frame is read. ``open_gel``: the open gel's frames (``--open``), or None."""
    start, stop = parse_reference(reference)
    open_range = None if open_gel is None else parse_reference(open_gel, "--open")
    if open_range is not None:
        check_open_before_reference(open_range, (start, stop))
    if fps is not None and not MIN_RATE_HZ <= fps <= MAX_RATE_HZ:
        raise InputError(
            f"--fps {fps:g}: expected a positive number of frames per second in "
            f"[{MIN_RATE_HZ:g}, {MAX_RATE_HZ:g}]"
        )
    profile = sensor_profile(sensor)
    estimator = estimator_for_sensor(profile, method)
    if calibration is not None:
        fit = load_calibration(calibration, profile.name, estimator.config, force, warn)
        estimator = estimator_for_sensor(profile, method, fit)
    inputs = [
        *([input_path] if isinstance(input_path, Path) else input_path),
        resolved_config_path(sensor, "sensors"),
        resolved_config_path(estimator.config_name, "estimators"),
        calibration,
    ]
    check_output_file(out_csv, inputs)
    source = open_source(input_path)
    rate_hz = fps or source.fps or estimator.profile.fps_hz

    if open_range is not None:
        open_frames = read_reference(source, *open_range, "--open")
        try:
            estimator.set_open_reference(open_frames)
        except ValueError as exc:
            raise InputError(f"open frames {open_range[0]}:{open_range[1]}: {exc}") from None
        doubt = open_gel_doubt(open_frames, open_range[0], next(source.frames(ReadLog())))
        if doubt:
            warn(f"--open {open_range[0]}:{open_range[1]}: {doubt}")
    reference_frames = read_reference(source, start, stop)
    try:
        estimator.set_reference(reference_frames)
    except ValueError as exc:
        raise InputError(f"reference frames {start}:{stop}: {exc}") from None

    sidecar = fallback_sidecar(out_csv)
    choice = None
    divergences: list[np.ndarray] | None = (
        [] if uses_recording(estimator, open_range is not None) else None
    )
    with atomic_text(out_csv, newline="") as handle:
        count, problems = _write_rows(estimator, source, rate_hz, handle, divergences)
        if problems and not allow_damaged:
            raise InputError(
                "; ".join(problems) + "; nothing written (pass --allow-damaged to estimate "
                "the frames that decoded)"
            )
        choice = recording_fallback(estimator, divergences or [], open_range is not None)
        if choice is not None:
            warn(f"{choice.message}: re-estimated ({sidecar})")
            estimator = choice.estimator
            estimator.set_reference(reference_frames)
            handle.seek(0)
            handle.truncate()
            count, problems = _write_rows(estimator, source, rate_hz, handle)
    if choice is None:
        sidecar.unlink(missing_ok=True)  # a previous run's choice, not this one's
    else:
        with atomic_text(sidecar) as handle:
            json.dump(choice.record, handle, indent=1)
    for problem in problems:
        warn(problem)
    return count


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog=job_prog("estimate"),
        description="Estimate in-grasp torques from recorded visuotactile frames.",
    )
    parser.add_argument(
        "input",
        type=Path,
        nargs="+",
        help="video file, folder of images, or image files (read in the order given)",
    )
    parser.add_argument(
        "--reference",
        default="0",
        help="zeroing reference: frame number N, or range A:B averaged (default 0)",
    )
    parser.add_argument(
        "--open",
        default=None,
        help="the open gel before the grasp: frame number N, or range A:B averaged "
        "(locates the contact for the grasp_centroid dipole origin)",
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
        "--calibration", type=Path, default=None, help="calibration YAML from tactile calibrate"
    )
    parser.add_argument(
        "--force",
        action="store_true",
        help="apply a calibration fitted for another sensor or estimator configuration",
    )
    parser.add_argument(
        "--fps",
        type=float,
        default=None,
        help="frame rate for time_s, Hz (default: the video's, else the sensor's)",
    )
    parser.add_argument(
        "--allow-damaged",
        action="store_true",
        help="estimate the frames of a damaged input that decode (warnings), instead of failing",
    )
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)

    def body() -> int:
        count = estimate_file(
            args.input,
            args.out,
            args.reference,
            args.sensor,
            args.method,
            args.calibration,
            args.fps,
            args.force,
            args.allow_damaged,
            open_gel=args.open,
        )
        print(f"estimate: wrote {count} rows to {args.out}")
        return 0

    return run_tool("estimate", body)
