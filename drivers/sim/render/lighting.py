"""The sensor's coloured LED lighting, fixed to the camera, and the final grey levels.

Each BGR channel of the image is a static shading (grey levels, float32 (H, W, 3)) times the
gel's reflectance (drivers/sim/render/gel_pattern.py) at that pixel. The shading does not move with
the gel. Lighting drift (LEDs warming up, a sagging supply) changes it slowly: a gain per
channel and a linear gradient across the image, both proportional to a dimensionless drift
level ``d`` (0: the lighting of the reference frames)::

    shading(d) = base * (1 + d * gain_c) + d * gradient_grey * (cos(a) * gx + sin(a) * gy)

with gx, gy in [-1, 1] from the left/top to the right/bottom pixel centre (gradient_grey:
grey levels added at the right edge for a = 0, the bottom edge for a = pi / 2).
"""

from __future__ import annotations

import cv2
import numpy as np

# Static shading of the B, G, R channels: a base level and a gradient direction (the LEDs'
# positions), in grey levels.
_LIGHT_BASE = (150.0, 170.0, 160.0)
_LIGHT_GRADIENT = ((25.0, 0.0), (-15.0, 20.0), (-10.0, -20.0))


def led_shading(shape_hw: tuple[int, int]) -> np.ndarray:
    """The reference shading, float32 (H, W, 3) BGR grey levels for reflectance 1."""
    height, width = shape_hw
    ys, xs = np.mgrid[0:height, 0:width].astype(np.float32)
    gx, gy = (xs - width / 2) / width, (ys - height / 2) / height
    planes = [
        base + ax * gx * 2 + ay * gy * 2 - 20.0 * (gx**2 + gy**2)
        for base, (ax, ay) in zip(_LIGHT_BASE, _LIGHT_GRADIENT, strict=True)
    ]
    return np.stack(planes, axis=2).astype(np.float32)


def drift_rate(
    base: np.ndarray,
    gain_per_level: tuple[float, float, float],
    gradient_grey_per_level: float,
    gradient_angle_rad: float,
) -> np.ndarray:
    """d shading / d level, float32 (H, W, 3) grey levels (see the module docstring), so that
    ``shading(d) = base + d * drift_rate(...)``."""
    height, width = base.shape[:2]
    gx = np.linspace(-1.0, 1.0, width, dtype=np.float32)[None, :]
    gy = np.linspace(-1.0, 1.0, height, dtype=np.float32)[:, None]
    plane = gradient_grey_per_level * (
        np.cos(gradient_angle_rad) * gx + np.sin(gradient_angle_rad) * gy
    )
    gains = np.asarray(gain_per_level, np.float32)
    return (base * gains + plane[:, :, None]).astype(np.float32)


def shade(
    reflectance: np.ndarray, shading: np.ndarray, noise: np.ndarray | None = None
) -> np.ndarray:
    """The uint8 BGR image (H, W, 3): ``shading * reflectance`` (float32 (H, W, 3) times
    (H, W)) plus optional pixel ``noise`` (float32 (H, W, 3), grey levels), rounded to the
    nearest grey level and saturated to [0, 255]."""
    reflectance3 = cv2.merge([reflectance, reflectance, reflectance])
    if noise is None:
        return cv2.multiply(shading, reflectance3, dtype=cv2.CV_8U)
    return cv2.add(cv2.multiply(shading, reflectance3), noise, dtype=cv2.CV_8U)
