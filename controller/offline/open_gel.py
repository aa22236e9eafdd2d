"""Whether the frames given as the open gel (``estimate.py --open``) look like it.

The open gel is the gel before the grasp, nothing touching: the recording's first frames
show it, and it does not change while it is seen. Frames that differ from each other or from
the recording's first frame far beyond the camera noise are not the open gel (a press, a
slip, the grasp itself), and taking them for it turns the grasp-centred dipole's origin (and
with it the tilt's sign) wrong. The comparison is on grey images smoothed over 2 px (noise
averages out, a marker's shift does not), after the best gain and offset (so a change of
exposure is no change): the 99.5th percentile of the remaining difference, in grey levels.
Camera noise of sigma 8 grey levels gives about 3; a grasp's shift of 1 px about 15.
"""

from __future__ import annotations

from collections.abc import Sequence

import cv2
import numpy as np

TOLERANCE_GREY = 6.0
SMOOTHING_PX = 2.0
PERCENTILE = 99.5


def change_grey(frame: np.ndarray, against: np.ndarray) -> float:
    """How much ``frame`` differs from ``against`` (same size, BGR uint8) beyond a change of
    gain and offset, in grey levels (see the module doc)."""
    x, y = _smoothed(against).ravel(), _smoothed(frame).ravel()
    design = np.stack([x, np.ones_like(x)], axis=1)
    coefficients, *_ = np.linalg.lstsq(design, y, rcond=None)
    return float(np.percentile(np.abs(y - design @ coefficients), PERCENTILE))


def open_gel_doubt(
    frames: Sequence[np.ndarray], first_number: int, recording_start: tuple[int, np.ndarray]
) -> str | None:
    """Why ``frames`` (numbered from ``first_number``) may not be the open gel, or None: a
    frame that differs from the first of them, or the recording's first frame
    (``recording_start``: its number and image) that differs from them, by more than
    ``TOLERANCE_GREY``."""
    start_number, start_image = recording_start
    candidates = [(first_number + i, frame) for i, frame in enumerate(frames[1:], 1)]
    if start_number < first_number and start_image.shape == frames[0].shape:
        candidates.insert(0, (start_number, start_image))
    for number, frame in candidates:
        change = change_grey(frame, frames[0])
        if change > TOLERANCE_GREY:
            return (
                f"frame {number} differs from frame {first_number} by {change:.1f} grey "
                f"levels, beyond the camera noise (tolerance {TOLERANCE_GREY:g}): something "
                "touched the gel, so these may not be the open gel (before the grasp, nothing "
                "touching); the tilt about the grasp's centre, and its sign, may be wrong"
            )
    return None


def _smoothed(frame: np.ndarray) -> np.ndarray:
    grey = cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY).astype(np.float32)
    return cv2.GaussianBlur(grey, (0, 0), SMOOTHING_PX)
