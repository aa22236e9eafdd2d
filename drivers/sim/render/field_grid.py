"""Displacement fields on grids of any resolution over an image: the convention, checks and
upsampling to every pixel.

A forward field ``u`` (h, w, 2) float, in px of the image ([..., 0] along x, the columns,
right; [..., 1] along y, the rows, down), says where the gel point seen at a grid node in the
reference image moves to; that is what optical flow from the reference to the current image
measures. A grid of (h, w) nodes covers an image of (H, W) px in the pixel-centre convention
(OpenCV's ``resize``): node (i, j) sits at the centre of its cell of W / w x H / h px, at::

    x = (j + 0.5) * W / w - 0.5,    y = (i + 0.5) * H / h - 0.5    (px, pixel centres at integers)

so a full-resolution field (h, w) = (H, W) has one node per pixel, and a 48 x 64 physics grid
over a 240 x 320 image has nodes at x = 2, 7, 12, ... px. Between nodes a field is
interpolated bilinearly (``GridUpsampler``); beyond the outermost nodes (the border strip
half a cell wide) it is extrapolated linearly, so affine fields are exact at any resolution.
(OpenCV's bicubic kernel, a = -0.75, does not reproduce linear functions: it bends an affine
field by up to 0.005 px at 5 px cells.)
The grid must have the image's aspect (square cells within 2 %): a transposed field is
refused.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

_ASPECT_TOLERANCE = 0.02


def check_field(displacement_px: np.ndarray, image_hw: tuple[int, int]) -> np.ndarray:
    """The field as float32 (h, w, 2), or ValueError naming the expected shape: at least 2 x 2
    nodes, square cells on the image of ``image_hw`` = (H, W) px, finite values."""
    field = np.asarray(displacement_px)
    height, width = image_hw
    shape = field.shape
    if field.ndim != 3 or shape[2] != 2 or min(shape[:2]) < 2:
        raise ValueError(
            f"displacement field: expected shape (h, w, 2) with the image's aspect, e.g. "
            f"{(height, width, 2)} (px), got {shape}"
        )
    cell_x, cell_y = width / shape[1], height / shape[0]
    if abs(cell_x - cell_y) > _ASPECT_TOLERANCE * max(cell_x, cell_y):
        raise ValueError(
            f"displacement field: expected the image's aspect {width}:{height} (e.g. "
            f"{(height, width, 2)} or {(height // 5, width // 5, 2)}), got shape {shape}"
        )
    if not np.all(np.isfinite(field)):
        raise ValueError("displacement field: expected finite values (px)")
    return np.ascontiguousarray(field, dtype=np.float32)


def pad_linear(grid: np.ndarray, rings: int) -> np.ndarray:
    """``grid`` (h, w, C) with ``rings`` extra nodes on each side, extrapolated linearly from
    the two outermost nodes along each axis (float32)."""
    h, w = grid.shape[:2]
    r = rings
    out = np.empty((h + 2 * r, w + 2 * r, *grid.shape[2:]), np.float32)
    out[r : r + h, r : r + w] = grid
    steps = np.arange(1, r + 1, dtype=np.float32).reshape(1, r, *([1] * (grid.ndim - 2)))
    rows = out[r : r + h]
    rows[:, :r] = grid[:, :1] + steps[:, ::-1] * (grid[:, :1] - grid[:, 1:2])
    rows[:, r + w :] = grid[:, -1:] + steps * (grid[:, -1:] - grid[:, -2:-1])
    steps = steps.reshape(r, 1, *steps.shape[2:])
    out[:r] = out[r : r + 1] + steps[::-1] * (out[r : r + 1] - out[r + 1 : r + 2])
    out[r + h :] = out[r + h - 1 : r + h] + steps * (
        out[r + h - 1 : r + h] - out[r + h - 2 : r + h - 1]
    )
    return out


class GridUpsampler:
    """Bilinear interpolation of an (h, w, C) float32 grid onto every pixel of an (H, W) image
    in the pixel-centre convention, extrapolated linearly beyond the outermost nodes, and
    over ``margin_px`` more pixels around the image: the result is (H + 2m, W + 2m, C) float32,
    entry (m, m) at pixel (0, 0).

    When a cell is a whole number of pixels along both axes this is ``cv2.resize`` of the
    padded grid (exact float weights); otherwise ``cv2.remap`` with precomputed fixed-point
    maps, whose positions are quantised to 1/32 of a cell (an error below 1/64 of the field's
    change across a cell)."""

    def __init__(
        self, grid_hw: tuple[int, int], image_hw: tuple[int, int], margin_px: int = 0
    ) -> None:
        (h, w), (height, width) = grid_hw, image_hw
        self.grid_hw, self.image_hw, self.margin_px = grid_hw, image_hw, margin_px
        m = margin_px
        self._method = "pad"
        self._rings = m
        if grid_hw == image_hw:
            return
        # rings enough that the margin lies between padded nodes
        self._rings = r = math.ceil((m + 0.5) * max(h / height, w / width) + 0.5)
        if height % h == 0 and width % w == 0:
            self._method = "resize"
            sy, sx = height // h, width // w
            self._size = ((w + 2 * r) * sx, (h + 2 * r) * sy)
            self._crop = (
                slice(r * sy - m, r * sy - m + height + 2 * m),
                slice(r * sx - m, r * sx - m + width + 2 * m),
            )
        else:
            self._method = "remap"
            xs = (np.arange(-m, width + m) + 0.5) * w / width - 0.5 + r
            ys = (np.arange(-m, height + m) + 0.5) * h / height - 0.5 + r
            mx, my = np.meshgrid(xs.astype(np.float32), ys.astype(np.float32))
            self._maps = cv2.convertMaps(mx, my, cv2.CV_16SC2)

    def __call__(self, grid: np.ndarray) -> np.ndarray:
        """The grid (h, w, C) at every pixel and margin pixel, float32."""
        if self._rings == 0:
            return grid
        padded = pad_linear(grid, self._rings)
        if self._method == "pad":
            return padded
        if self._method == "resize":
            return cv2.resize(padded, self._size, interpolation=cv2.INTER_LINEAR)[self._crop]
        return cv2.remap(padded, *self._maps, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
