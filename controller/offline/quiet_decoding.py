"""Image and video decoding without the C libraries' own messages on the terminal.

A damaged input makes the decoders write to the process's stderr themselves: OpenCV's
``[ERROR:0@...]`` log lines (BMP, TIFF), libpng's ``libpng error: IDAT: CRC error``,
libjpeg's ``Premature end of JPEG file``, OpenCV's AVI parser's ``Unexpected element``. The
last three bypass OpenCV's log level (``cv2.utils.logging``, ``OPENCV_LOG_LEVEL``), so the
tools decode with file descriptor 2 pointed at /dev/null and report the damage in their own
one line (controller/offline/video.py, estimate_cli.py, appearance/stats_cli.py).
"""

from __future__ import annotations

import os
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import cv2
import numpy as np


@contextmanager
def native_stderr_muted() -> Iterator[None]:
    """Within the block, what C code writes to stderr (fd 2) is discarded; Python's
    ``sys.stderr`` is flushed first. The main thread's decoding only: fd 2 is the process's."""
    sys.stderr.flush()
    try:
        saved = os.dup(2)
    except OSError:  # no stderr at all: nothing to keep quiet
        yield
        return
    try:
        with open(os.devnull, "wb") as null:
            os.dup2(null.fileno(), 2)
        yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)


def read_image(path: Path) -> np.ndarray | None:
    """The BGR image at ``path``, or None if it does not decode (quietly)."""
    with native_stderr_muted():
        return cv2.imread(str(path), cv2.IMREAD_COLOR)
