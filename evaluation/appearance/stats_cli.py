"""The appearance statistics of gel images, real or rendered (evaluation/appearance/stats.py).

    python -m evaluation gel_stats INPUT [INPUT ...] [--size 320x240|native] [--every K]
        [--json OUT.json]

Each INPUT is an image file, a folder of images (natural sort order) or a video OpenCV can
read. Each frame is first brought to the working size ``--size`` (default 320x240, the
sensors' working image: turned a quarter if its orientation differs, scaled to cover and
centre-cropped, as the renderer does with real captures; ``native`` measures it as it is).
A folder's or video's statistics are the median over its frames (every K-th with
``--every K``). The tool prints a Markdown table with one column per input and writes, with
``--json``, ``{input: {"frames": n, "stats": {...}, "per_frame": [...]}}``.

Bad input (a missing or unreadable file, an empty folder, a bad size) prints one line
``gel_stats: error: ...`` and exits with code 2.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from controller.cli.estimate import IMAGE_SUFFIXES, InputError, open_source
from controller.offline.quiet_decoding import read_image
from controller.offline.video import ReadLog
from core.subcommands import job_prog
from drivers.sim.render.real_texture import fit_to_size
from evaluation.appearance.stats import AppearanceStats, format_table, measure, summarise


def parse_size(text: str) -> tuple[int, int] | None:
    """``'WxH'`` -> (H, W); ``'native'`` -> None; InputError on anything else."""
    if text == "native":
        return None
    match = re.fullmatch(r"(\d+)x(\d+)", text)
    if not match or min(int(match.group(1)), int(match.group(2))) < 32:
        raise InputError(f"--size '{text}': expected WxH of at least 32x32 px, or native")
    return int(match.group(2)), int(match.group(1))


def frames_of(path: Path, every: int) -> Iterator[np.ndarray]:
    """The BGR frames of an image file, image folder or video (every ``every``-th)."""
    if path.is_file() and path.suffix.lower() in IMAGE_SUFFIXES:
        image = read_image(path)
        if image is None:
            raise InputError(f"cannot read image '{path}'")
        yield image
        return
    for index, (_, frame) in enumerate(open_source(path).frames(ReadLog())):
        if index % every == 0:
            yield frame


def stats_of(
    path: Path, shape_hw: tuple[int, int] | None, every: int = 1
) -> tuple[AppearanceStats, list[AppearanceStats]]:
    """(the median statistics, each frame's) of one input."""
    per_frame = []
    for frame in frames_of(path, every):
        image = frame if shape_hw is None else fit_to_size(frame, shape_hw)
        try:
            per_frame.append(measure(image))
        except ValueError as exc:
            raise InputError(f"'{path}': {exc}") from None
    return summarise(per_frame), per_frame


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog=job_prog("gel_stats"),
        description="Appearance statistics (markers, shading spectrum and colour, noise) of "
        "gel images or videos, real or rendered.",
    )
    parser.add_argument("inputs", nargs="+", type=Path, help="image, image folder or video")
    parser.add_argument(
        "--size", default="320x240", help="working size WxH to measure at, or native"
    )
    parser.add_argument("--every", type=int, default=1, help="measure every K-th frame")
    parser.add_argument("--json", type=Path, default=None, help="write the statistics here")
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        shape_hw = parse_size(args.size)
        if args.every < 1:
            raise InputError(f"--every {args.every}: expected a positive integer")
        results = {str(path): stats_of(path, shape_hw, args.every) for path in args.inputs}
        if args.json is not None:
            document = {
                name: {
                    "frames": len(frames),
                    "stats": median.as_dict(),
                    "per_frame": [s.as_dict() for s in frames],
                }
                for name, (median, frames) in results.items()
            }
            try:
                args.json.parent.mkdir(parents=True, exist_ok=True)
                args.json.write_text(json.dumps(document, indent=1) + "\n")
            except OSError as exc:
                raise InputError(f"cannot write '{args.json}': {exc.strerror}") from None
    except InputError as exc:
        print(f"gel_stats: error: {exc}", file=sys.stderr)
        return 2
    print(format_table({name: median for name, (median, _) in results.items()}))
    return 0
