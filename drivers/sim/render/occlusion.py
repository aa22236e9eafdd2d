"""Static blobs over the gel (a torn patch, dirt on the lens) that do not move with it.

Inside a blob the camera sees a fixed region with its own texture instead of the gel, so
optical flow there reads zero whatever the gel does. The blobs are ellipses with soft edges
about a pixel wide; they are blended into the gel's warped reflectance before the lighting,
so lighting drift and blur act on them like on the gel.
"""

from __future__ import annotations

import cv2
import numpy as np

_EDGE_PX = 0.7  # softness of a blob's edge (tanh width), px


class Occlusion:
    """``count`` seeded elliptic blobs on an (H, W) image: centres uniform over the image,
    semi-major axis ``size_px`` px, semi-minor 50-100 % of it, any orientation; inside, a
    static reflectance of mean ``reflectance`` with a speckle of relative std ``texture``.

    ``alpha`` (H, W) float32 in [0, 1] is the blobs' cover (1 inside, 0 on the free gel)."""

    def __init__(
        self,
        shape_hw: tuple[int, int],
        count: int,
        size_px: float,
        reflectance: float,
        texture: float,
        rng: np.random.Generator,
    ) -> None:
        height, width = shape_hw
        ys, xs = np.mgrid[0:height, 0:width].astype(np.float32)
        alpha = np.zeros(shape_hw, np.float32)
        for _ in range(count):
            cx, cy = rng.uniform(0, width), rng.uniform(0, height)
            minor = size_px * rng.uniform(0.5, 1.0)
            angle = rng.uniform(0, np.pi)
            c, s = np.cos(angle), np.sin(angle)
            along = (xs - cx) * c + (ys - cy) * s
            across = -(xs - cx) * s + (ys - cy) * c
            # distance outside the ellipse, px, measured along the minor-axis scale
            outside = (np.hypot(along / size_px, across / minor) - 1.0) * minor
            np.maximum(alpha, 0.5 * (1.0 - np.tanh(outside / _EDGE_PX)), out=alpha)
        speckle = cv2.GaussianBlur(rng.standard_normal(shape_hw).astype(np.float32), (0, 0), 2.0)
        speckle *= texture / max(float(speckle.std()), 1e-6)
        self.alpha = alpha
        self._keep = (1.0 - alpha).astype(np.float32)
        self._static = (alpha * reflectance * (1.0 + speckle)).astype(np.float32)

    def apply(self, gel: np.ndarray) -> np.ndarray:
        """The reflectance the camera sees: the warped gel ``gel`` (H, W) or (H, W, C) float32
        where free, the static blobs where covered, blended at their soft edges (a new
        array)."""
        if gel.ndim == 3:
            return gel * self._keep[..., None] + self._static[..., None]
        return cv2.add(cv2.multiply(gel, self._keep), self._static)
