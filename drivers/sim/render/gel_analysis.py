"""Finding the printed markers of a gel image and the smooth lighting between them.

Shared by the real-texture appearance (drivers/sim/render/real_texture.py: where the markers
are, and the static LED shading to divide out) and the appearance statistics
(evaluation/appearance/stats.py). Images are (H, W) grey or (H, W, C) colour float32 or uint8 grey
levels; positions are px (x right, y down, pixel centres at integers).

A marker is a dark, compact blob: a connected region darker than the image's grey-level
closing (the markers closed away by a disc wider than the largest marker) by more than
both Otsu's threshold on that darkness and ``min_darkness_grey``, whose darkest pixel is
darker than the closing by at least ``MIN_RELATIVE_DARKNESS`` of it (a texture's dark specks
are shallower than printed ink), with an area of a disc of
diameter 2 to ``max_diameter_px`` and a bounding box that it fills by at least half, about as
wide as tall. Its centre is the darkness-weighted centroid. A gel without markers (DIGIT, a
bare GelSight) gives none: its smudges are fainter than ``min_darkness_grey``.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from scipy import ndimage

MAX_DIAMETER_PX = 16.0
"""Largest marker diameter looked for, px (markers at 320 x 240 are 5-10 px)."""

MIN_DARKNESS_GREY = 20.0
"""Least darkness of a marker below the closed background, grey levels."""

MIN_RELATIVE_DARKNESS = 0.45
"""Least darkness of a marker's darkest pixel as a fraction of the closed background (real
markers: about 0.8; a dense speckle's darkest specks: about 0.35)."""

MASK_MARGIN_PX = 2
"""Pixels added around each marker's blob to cover its soft edge."""

OCTAVE_SIGMAS_PX = (0.0, 1.0, 2.0, 4.0, 8.0, 16.0)
"""Gaussian sigmas (px at 320 px width; 0: no blur) bounding the octave bands in which the
shading between markers is measured (evaluation/appearance/stats.py) and the ``realistic``
texture is drawn (drivers/sim/render/realistic.py): band k lies between sigmas k and k + 1."""


@dataclass(frozen=True)
class Markers:
    """The markers found in an image: ``centres_px`` (N, 2) float64 (x, y) and ``mask`` (H, W)
    bool, True on a marker's blob grown by ``MASK_MARGIN_PX`` (its soft edge included)."""

    centres_px: np.ndarray
    mask: np.ndarray


def grey_of(image: np.ndarray) -> np.ndarray:
    """The image as float32 grey levels (H, W): OpenCV's BGR luma for colour images."""
    image = np.asarray(image)
    if image.ndim == 3:
        image = cv2.cvtColor(image.astype(np.float32), cv2.COLOR_BGR2GRAY)
    return image.astype(np.float32)


def find_markers(
    image: np.ndarray,
    max_diameter_px: float = MAX_DIAMETER_PX,
    min_darkness_grey: float = MIN_DARKNESS_GREY,
) -> Markers:
    """The dark printed markers of a grey or BGR image (see the module docstring)."""
    grey = grey_of(image)
    radius = int(np.ceil(max_diameter_px / 2)) + 2
    disc = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * radius + 1, 2 * radius + 1))
    closed = cv2.morphologyEx(grey, cv2.MORPH_CLOSE, disc)
    darkness = closed - grey
    otsu, _ = cv2.threshold(
        np.clip(darkness, 0, 255).astype(np.uint8), 0, 255, cv2.THRESH_BINARY | cv2.THRESH_OTSU
    )
    blobs = (darkness > max(otsu, min_darkness_grey)).astype(np.uint8)
    count, labels, stats, _ = cv2.connectedComponentsWithStats(blobs, connectivity=8)
    area = stats[:, cv2.CC_STAT_AREA].astype(float)
    box_w = stats[:, cv2.CC_STAT_WIDTH].astype(float)
    box_h = stats[:, cv2.CC_STAT_HEIGHT].astype(float)
    relative = darkness / np.maximum(closed, 1.0)
    deepest = np.asarray(ndimage.maximum(relative, labels, np.arange(count)))
    keep = (
        (deepest >= MIN_RELATIVE_DARKNESS)
        & (area >= np.pi)
        & (area <= np.pi * (max_diameter_px / 2) ** 2)
        & (area >= 0.5 * box_w * box_h)
        & (np.maximum(box_w, box_h) <= 2 * np.minimum(box_w, box_h))
    )
    keep[0] = False
    index = labels.ravel()
    weights = np.where(keep[labels], darkness, 0.0).ravel()
    ys, xs = np.indices(grey.shape)
    total = np.bincount(index, weights, minlength=count)
    with np.errstate(invalid="ignore", divide="ignore"):
        cx = np.bincount(index, weights * xs.ravel(), minlength=count) / total
        cy = np.bincount(index, weights * ys.ravel(), minlength=count) / total
    centres = np.stack([cx[keep], cy[keep]], axis=1)
    grow = cv2.getStructuringElement(
        cv2.MORPH_ELLIPSE, (2 * MASK_MARGIN_PX + 1, 2 * MASK_MARGIN_PX + 1)
    )
    mask = cv2.dilate(keep[labels].astype(np.uint8), grow).astype(bool)
    return Markers(centres, mask)


def masked_blur(image: np.ndarray, valid: np.ndarray, sigma_px: float) -> np.ndarray:
    """Gaussian blur of ``image`` (H, W) or (H, W, C) over the ``valid`` (H, W) pixels only
    (normalised convolution), float32 of the image's shape: a smooth fill-in of the invalid
    ones (markers) from their surroundings. Borders are mirrored."""
    weight = cv2.GaussianBlur(valid.astype(np.float32), (0, 0), sigma_px)
    weighted = np.asarray(image, np.float32) * (
        valid[..., None] if np.ndim(image) == 3 else valid
    ).astype(np.float32)
    blurred = cv2.GaussianBlur(weighted, (0, 0), sigma_px)
    weight = np.maximum(weight, 1e-6)
    return blurred / (weight[..., None] if blurred.ndim == 3 else weight)
