"""Real gel captures as textures: the ``real:<name>`` appearances of the renderer.

The captures are in drivers/sim/render/real_gels/ (their README gives source and licence).
A capture is brought to the sensor's working size (``fit_to_size``) and split into what the
camera's LEDs give and what the gel carries (``split_capture``):

    image = shading * reflectance        (per B, G, R channel)

The **shading** is the capture's lighting between the markers, smoothed by a Gaussian of
``SHADING_SIGMA_PX`` (16 px at 320 px width, wavelengths above about 100 px) over the
marker-free pixels only: the LED gradients, fixed to the camera, which stay put while the gel
moves, as in the procedural renderer (drivers/sim/render/lighting.py). The **reflectance** is
the rest, image / shading per channel: markers, their coloured fringes, dust, the finer
shading, which move with the gel when the renderer warps it. At zero displacement the
renderer gives back the capture itself (up to rounding).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from drivers.sim.render.gel_analysis import Markers, find_markers, masked_blur

REAL_GELS_DIR = Path(__file__).resolve().parent / "real_gels"
"""The captures shipped with the package."""

_SUFFIXES = (".png", ".jpg")

SHADING_SIGMA_PX = 16.0
"""Gaussian sigma of the static shading at 320 px image width, px."""

_FILL_SIGMA_PX = 3.0  # smoothing that fills a worn-off marker from its surroundings, px


def real_gel_names() -> tuple[str, ...]:
    """The names of the shipped captures (file stems), sorted."""
    return tuple(sorted(p.stem for p in REAL_GELS_DIR.iterdir() if p.suffix in _SUFFIXES))


def load_capture(name: str) -> np.ndarray:
    """The capture ``name`` as stored, uint8 BGR (H, W, 3); ValueError naming the known ones."""
    paths = [REAL_GELS_DIR / f"{name}{suffix}" for suffix in _SUFFIXES]
    path = next((p for p in paths if p.is_file()), None)
    if path is None:
        raise ValueError(
            f"real gel '{name}': expected one of {', '.join(real_gel_names())} "
            f"(images in {REAL_GELS_DIR})"
        )
    image = cv2.imread(str(path), cv2.IMREAD_COLOR)
    if image is None:
        raise ValueError(f"real gel '{name}': cannot decode {path}")
    return image


def fit_to_size(image: np.ndarray, shape_hw: tuple[int, int]) -> np.ndarray:
    """``image`` (h, w[, C]) brought to ``shape_hw`` = (H, W): turned a quarter clockwise if
    one is portrait and the other landscape, scaled (area averaging to shrink, bilinear to
    enlarge) just enough to cover (H, W), and cropped about its centre."""
    height, width = shape_hw
    if (image.shape[0] > image.shape[1]) != (height > width) and image.shape[0] != image.shape[1]:
        image = cv2.rotate(image, cv2.ROTATE_90_CLOCKWISE)
    scale = max(height / image.shape[0], width / image.shape[1])
    if scale != 1.0:
        size = (
            max(width, round(image.shape[1] * scale)),
            max(height, round(image.shape[0] * scale)),
        )
        method = cv2.INTER_AREA if scale < 1 else cv2.INTER_LINEAR
        image = cv2.resize(image, size, interpolation=method)
    y0 = (image.shape[0] - height) // 2
    x0 = (image.shape[1] - width) // 2
    return np.ascontiguousarray(image[y0 : y0 + height, x0 : x0 + width])


@dataclass(frozen=True)
class Capture:
    """A capture split for rendering: ``shading`` and ``reflectance`` float32 (H, W, 3) with
    shading * reflectance = the image, and its ``markers``."""

    shading: np.ndarray
    reflectance: np.ndarray
    markers: Markers

    def without_markers(self, worn: np.ndarray) -> np.ndarray:
        """The reflectance with the markers ``worn`` (bool (N,) over ``markers.centres_px``)
        filled in from their surroundings (marker dropout)."""
        if not np.any(worn):
            return self.reflectance
        _, labels = cv2.connectedComponents(self.markers.mask.astype(np.uint8))
        centres = np.rint(self.markers.centres_px[worn]).astype(int)
        ids = labels[centres[:, 1], centres[:, 0]]
        gone = np.isin(labels, ids[ids > 0])
        filled = masked_blur(self.reflectance, ~self.markers.mask, _FILL_SIGMA_PX)
        return np.where(gone[..., None], filled, self.reflectance).astype(np.float32)


def split_capture(image: np.ndarray) -> Capture:
    """Split a uint8 BGR capture at the working size (see the module docstring)."""
    markers = find_markers(image)
    colour = image.astype(np.float32)
    sigma = SHADING_SIGMA_PX * image.shape[1] / 320
    shading = np.maximum(masked_blur(colour, ~markers.mask, sigma), 1.0)
    return Capture(shading, colour / shading, markers)
