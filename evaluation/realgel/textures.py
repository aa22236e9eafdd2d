"""Real gel images (evaluation/data/real_gels/, see its README) used as textures.

Each is returned as a float32 BGR image of 240 x 320 px (landscape; the portrait captures are
turned a quarter turn clockwise), in grey levels 0-255, so that warping it does not quantise
twice.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

DATA_DIR = Path(__file__).resolve().parent.parent / "data" / "real_gels"
SIZE_HW = (240, 320)


@dataclass(frozen=True)
class Texture:
    """A real capture: its file, the sensor profile it belongs to (configs/sensors/) and
    whether its gel carries printed markers."""

    name: str
    file: str
    sensor: str
    markers: bool


TEXTURES = {
    t.name: t
    for t in (
        Texture("gelsight_markers_a", "gelsight_markers_a.png", "gelsight_mini", True),
        Texture("gelsight_markers_b", "gelsight_markers_b.png", "gelsight_mini", True),
        Texture("gelsight_background", "gelsight_background.png", "gelsight_mini", False),
        Texture("digit_background_a", "digit_background_a.png", "digit", False),
        Texture("digit_background_b", "digit_background_b.jpg", "digit", False),
    )
}


def load_texture(name: str) -> np.ndarray:
    """The capture ``name`` (a key of TEXTURES) as float32 BGR (240, 320, 3)."""
    path = DATA_DIR / TEXTURES[name].file
    image = cv2.imread(str(path), cv2.IMREAD_COLOR)
    if image is None:
        raise FileNotFoundError(f"cannot read the real gel image {path}")
    if image.shape[:2] == SIZE_HW[::-1]:
        image = cv2.rotate(image, cv2.ROTATE_90_CLOCKWISE)
    if image.shape[:2] != SIZE_HW:
        raise ValueError(f"{path}: expected 320 x 240 px in either orientation, got {image.shape}")
    return image.astype(np.float32)
