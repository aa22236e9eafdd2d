"""Real gel images (drivers/sim/render/real_gels/, see its README) used as textures.

Each is returned as a float32 BGR image of 240 x 320 px (landscape; the portrait captures are
turned a quarter turn clockwise), in grey levels 0-255, so that warping it does not quantise
twice.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from drivers.sim.render.real_texture import REAL_GELS_DIR

DATA_DIR = REAL_GELS_DIR
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


ILLUMINATION_SIGMA_PX = 8.0


def split_illumination(texture: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(illumination, albedo) with ``texture = illumination * albedo``, float32 BGR.

    The illumination is the LED shading, fixed to the camera: per channel, the texture with
    its dark markers closed away (grey-level closing with a 15 px disk, wider than a marker)
    and smoothed (Gaussian, sigma ``ILLUMINATION_SIGMA_PX``). The albedo is the rest: the
    markers and the gel's fine texture, which move with the gel."""
    disk = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (15, 15))
    closed = cv2.morphologyEx(texture, cv2.MORPH_CLOSE, disk)
    illumination = cv2.GaussianBlur(closed, (0, 0), ILLUMINATION_SIGMA_PX)
    illumination = np.maximum(illumination, 1.0)
    return illumination, texture / illumination


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
