"""The trial a SIGKILL benchmark kills (evaluation/bench/episode.py): a real-time simulated
usb_c trial writing its episode into OUT, with an observer that stores each tick's start
(s on the loop's clock) and the ``time.monotonic`` it was noted at in the 16-byte file MARK,
so the parent knows, after the kill, the newest tick the loop had made and when.

    python -m evaluation.bench.episode_child OUT MARK SEED OVERRIDE...
"""

from __future__ import annotations

import mmap
import struct
import sys
import time
from pathlib import Path

from controller.episode.session import EpisodeOptions
from controller.loop import TickRecord
from controller.run import load_task
from evaluation.trials.trial import run


def main(argv: list[str]) -> int:
    out, mark, seed, overrides = Path(argv[0]), Path(argv[1]), int(argv[2]), argv[3:]
    with mark.open("r+b") as handle, mmap.mmap(handle.fileno(), 16) as shared:

        def note(tick: TickRecord) -> None:
            shared[:16] = struct.pack("<dd", tick.timing.start_s, time.monotonic())

        task = load_task("usb_c", overrides)
        run(task, "dipole", seed, out_dir=out, episode=EpisodeOptions(), realtime=True,
            observers=[note])  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
