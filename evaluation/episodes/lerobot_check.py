"""Load an export (``replay export ... --lerobot DIR``) with the real ``lerobot`` package,
offline, and check every frame (``make check-lerobot``; docs/EPISODES.md, "Checked with
LeRobot itself").

Runs in the separate Python 3.12 environment that ``make check-lerobot`` makes (``lerobot``
needs Python 3.12 and torch; the project does not import it), with the project's folder on
``PYTHONPATH`` for ``python -m evaluation check_lerobot`` (evaluation/tools.py,
core/subcommands.py, core/entry_point.py: standard library only); it imports nothing else of the
project. For each ``--episode TASK=FRAMES`` (in episode order: the task sentence and the
number of tactile frames its episode file holds) it checks, through ``LeRobotDataset``:

* the episode has FRAMES rows (one per tactile frame: none dropped, none repeated),
  ``frame_index`` 0..FRAMES-1 and ``timestamp == frame_index / fps`` (within 1e-6 s);
* every row's ``task`` string is TASK;
* every row's image, decoded by LeRobot at ``from_timestamp + timestamp`` within its
  ``tolerance_s``, equals PyAV's own decoding of the video's frame at that index (within
  one grey level: LeRobot returns float32 in [0, 1]).

Prints a short report; exit 0 when every check passes, 1 when one fails, 2 (one line) for
bad arguments or a dataset LeRobot cannot load.

    PYTHONPATH=. .venv-lerobot/bin/python -m evaluation check_lerobot DIR \
        --episode "insert the usb_c plug=321" ...
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

from core.subcommands import job_prog

os.environ.setdefault("HF_HUB_OFFLINE", "1")  # a local root: nothing is downloaded
os.environ.setdefault("HF_DATASETS_OFFLINE", "1")

IMAGE_KEY = "observation.images.tactile"
VIDEO_BACKEND = "pyav"
"""torchcodec needs FFmpeg's shared libraries on the machine; PyAV's wheel carries its own."""
TIMESTAMP_TOLERANCE_S = 1e-6


def episode_argument(text: str) -> tuple[str, int]:
    task, _, frames = text.rpartition("=")
    if not task or not frames.isdigit() or int(frames) < 1:
        raise argparse.ArgumentTypeError(f"expected TASK=FRAMES (a positive count), got {text!r}")
    return task, int(frames)


def video_frames(path: Path):  # type: ignore[no-untyped-def]
    """Every frame of the MP4 at ``path`` as PyAV decodes it: RGB uint8, H x W x 3."""
    import av

    with av.open(str(path)) as container:
        return [frame.to_ndarray(format="rgb24") for frame in container.decode(video=0)]


def check(root: Path, expected: list[tuple[str, int]]) -> list[str]:
    """The failures (empty when everything passes); prints the report as it goes."""
    import lerobot
    import numpy as np
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    began = time.monotonic()
    dataset = LeRobotDataset("local/tactile-insertion", root=root, video_backend=VIDEO_BACKEND)
    meta = dataset.meta
    print(f"lerobot {lerobot.__version__} ({VIDEO_BACKEND} decoder), dataset {root}: "
          f"{dataset.num_episodes} episodes, {dataset.num_frames} frames at {meta.fps} fps, "
          f"tolerance_s {dataset.tolerance_s}")  # fmt: skip
    failures: list[str] = []
    if dataset.num_episodes != len(expected):
        failures.append(f"{dataset.num_episodes} episodes, expected {len(expected)}")
        return failures
    video_path = root / meta.get_video_file_path(0, IMAGE_KEY)
    decoded = video_frames(video_path)
    index = 0
    for episode, (task, frames) in enumerate(expected):
        record = meta.episodes[episode]
        first = round(record[f"videos/{IMAGE_KEY}/from_timestamp"] * meta.fps)
        length = int(record["length"])
        worst, tasks, bad_times = 0, set(), 0
        for row in range(length):
            item = dataset[index + row]
            frame_index = int(item["frame_index"])
            timestamp = float(item["timestamp"])
            if frame_index != row or abs(timestamp - row / meta.fps) > TIMESTAMP_TOLERANCE_S:
                bad_times += 1
            tasks.add(item["task"])
            image = item[IMAGE_KEY].numpy()  # C x H x W, float32 in [0, 1]
            pixels = np.round(image.transpose(1, 2, 0) * 255).astype(int)
            worst = max(worst, int(np.abs(pixels - decoded[first + row]).max()))
        index += length
        print(f"episode {episode}: {length} rows for {frames} tactile frames; task "
              f"{sorted(tasks)}; {length - bad_times} of {length} frame_index/timestamp = k / fps; "
              f"images vs PyAV's frames {first}..{first + length - 1}: largest difference {worst} "
              "grey levels")  # fmt: skip
        if length != frames:
            failures.append(f"episode {episode}: {length} rows, expected {frames}")
        if tasks != {task}:
            failures.append(f"episode {episode}: tasks {sorted(tasks)}, expected {task!r}")
        if bad_times:
            failures.append(f"episode {episode}: {bad_times} rows off frame_index / fps")
        if worst > 1:
            failures.append(f"episode {episode}: an image differs from PyAV's by {worst}")
    if len(decoded) != dataset.num_frames:
        failures.append(f"the video has {len(decoded)} frames for {dataset.num_frames} rows")
    verdict = "all checks passed" if not failures else f"{len(failures)} checks FAILED"
    print(f"checked {index} frames in {time.monotonic() - began:.1f} s: {verdict}")
    return failures


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog=job_prog("check_lerobot"), description=__doc__.splitlines()[0]
    )
    parser.add_argument("root", type=Path, metavar="DIR", help="the exported dataset")
    parser.add_argument(
        "--episode", type=episode_argument, action="append", required=True,
        metavar="TASK=FRAMES", help="each episode's task and frame count",
    )  # fmt: skip
    args = parser.parse_args(argv)
    if not (args.root / "meta" / "info.json").is_file():
        print(f"check_lerobot: error: '{args.root}': expected a LeRobot dataset folder "
              "(meta/info.json)", file=sys.stderr)  # fmt: skip
        return 2
    failures = check(args.root, args.episode)
    for failure in failures:
        print(f"FAILED: {failure}")
    return 1 if failures else 0
