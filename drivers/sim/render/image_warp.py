"""Fast, nearly exact resampling of a float image at backward maps.

``SplineWarper`` tabulates the image's cubic-spline interpolant (mirror boundaries, as
``scipy.ndimage.map_coordinates(order=3, mode="mirror")``) every 1/2 px once, and each warp
interpolates that table bilinearly with ``cv2.remap``. Measured with the project's optical
flow, this is as accurate as spline resampling at full float precision and as fast as
OpenCV's bicubic remap (about 0.3 ms at 320 x 240 on one core); OpenCV's bicubic kernel
(a = -0.75) itself biases sub-pixel flow about twice as much, and bilinear interpolation on
the image's own pixels blurs it by an amount that depends on the sub-pixel position.

``cv2.remap`` quantises sampling positions to 1/32 of a table step (``INTER_BITS`` = 5), i.e.
to 1/64 px: a warped image's displacement is true to within 1/128 px (rounding) plus the
map's own error. Converting the maps to fixed point first (``cv2.convertMaps``) gains nothing
for a map used once: remap converts them internally (measured the same speed).
"""

from __future__ import annotations

import cv2
import numpy as np
from scipy.ndimage import spline_filter

# Cubic B-spline weights of the coefficients around a sample at a node (offsets -1, 0, 1)
# and half-way between nodes i and i + 1 (offsets -1.5, -0.5, 0.5, 1.5; anchored at i).
_AT_NODE = np.array([1.0, 4.0, 1.0], np.float32) / 6.0
_HALF_WAY = np.array([1.0, 23.0, 23.0, 1.0], np.float32) / 48.0


def half_pixel_table(image: np.ndarray) -> np.ndarray:
    """The cubic-spline interpolant of ``image`` (H, W) sampled every 1/2 px, float32
    (2H - 1, 2W - 1): entry (2i, 2j) is pixel (i, j) itself."""
    height, width = image.shape
    coefficients = spline_filter(image, order=3, mode="mirror").astype(np.float32)
    table = np.empty((2 * height - 1, 2 * width - 1), np.float32)
    for ry, kernel_y in enumerate((_AT_NODE, _HALF_WAY)):
        for rx, kernel_x in enumerate((_AT_NODE, _HALF_WAY)):
            values = cv2.sepFilter2D(
                coefficients,
                cv2.CV_32F,
                kernel_x,
                kernel_y,
                anchor=(1, 1),
                borderType=cv2.BORDER_REFLECT_101,
            )
            table[ry::2, rx::2] = values[: height - ry, : width - rx]
    return table


class SplineWarper:
    """``warper(backward)`` -> the image (H, W) or (H, W, C) float32 (C <= 4) resampled at
    the backward map (H, W, 2) px (image(y) = source(backward(y))), mirrored beyond the
    border; each channel has its own table and one ``cv2.remap`` samples them all."""

    def __init__(self, image: np.ndarray) -> None:
        self.image = image
        if image.ndim == 2:
            self._table = half_pixel_table(image)
        else:
            self._table = cv2.merge([half_pixel_table(channel) for channel in cv2.split(image)])

    def __call__(self, backward_px: np.ndarray) -> np.ndarray:
        in_table = cv2.add(backward_px, backward_px)  # 2 x, exactly (a scalar product is 5x slower)
        return cv2.remap(
            self._table, in_table, None, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT_101
        )
