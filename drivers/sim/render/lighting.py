"""The sensor's coloured LED lighting, fixed to the camera, and the final grey levels.

Each BGR channel of the image is a static shading (grey levels, float32 (H, W, 3)) times the
gel's reflectance (drivers/sim/render/gel_pattern.py) at that pixel. The shading does not move with
the gel. Lighting drift (LEDs warming up, a sagging supply) changes it slowly: a gain per
channel and a linear gradient across the image, both proportional to a dimensionless drift
level ``d`` (0: the lighting of the reference frames)::

    shading(d) = base * (1 + d * gain_c) + d * gradient_grey * (cos(a) * gx + sin(a) * gy)

with gx, gy in [-1, 1] from the left/top to the right/bottom pixel centre (gradient_grey:
grey levels added at the right edge for a = 0, the bottom edge for a = pi / 2).

``led_shading`` is the ``speckle`` appearance's fixed shading; ``random_led_shading`` the
``realistic`` one's, a seeded smooth coloured field with the channel means, spreads and
correlations measured on real captures (drivers/sim/render/realistic.py).
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


def random_led_shading(
    shape_hw: tuple[int, int],
    mean_bgr: tuple[float, float, float],
    spread_bgr: tuple[float, float, float],
    correlation_bg_br_gr: tuple[float, float, float],
    scale_px: float,
    rng: np.random.Generator,
) -> np.ndarray:
    """A smooth coloured shading, float32 (H, W, 3) BGR grey levels for reflectance 1: three
    Gaussian random fields of correlation length ``scale_px`` (white noise blurred by a
    Gaussian of that sigma), mixed so that over the image each channel has exactly the mean
    ``mean_bgr`` and standard deviation ``spread_bgr`` (grey levels) and the channels have
    the correlation coefficients ``correlation_bg_br_gr`` (B-G, B-R, G-R). Clipped at 0."""
    height, width = shape_hw
    step = max(1, int(scale_px // 8))  # draw on a coarse grid, then upsample: the field is smooth
    small = rng.standard_normal((height // step + 2, width // step + 2, 3)).astype(np.float32)
    small = cv2.GaussianBlur(small, (0, 0), scale_px / step, borderType=cv2.BORDER_REFLECT)
    fields = cv2.resize(small, (width + 2 * step, height + 2 * step), interpolation=cv2.INTER_CUBIC)
    z = fields[step : step + height, step : step + width].reshape(-1, 3).astype(np.float64)
    z -= z.mean(axis=0)
    z = z @ np.linalg.inv(np.linalg.cholesky(z.T @ z / len(z))).T  # exactly white
    bg, br, gr = correlation_bg_br_gr
    mixing = np.linalg.cholesky(np.array([[1.0, bg, br], [bg, 1.0, gr], [br, gr, 1.0]]))
    shading = (z @ mixing.T) * np.asarray(spread_bgr) + np.asarray(mean_bgr)
    return np.maximum(shading, 0.0).reshape(height, width, 3).astype(np.float32)


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
    (H, W), or times (H, W, 3) for a reflectance per channel) plus optional pixel ``noise``
    (float32 (H, W, 3), grey levels), rounded to the nearest grey level and saturated to
    [0, 255]."""
    reflectance3 = (
        reflectance if reflectance.ndim == 3 else cv2.merge([reflectance, reflectance, reflectance])
    )
    if noise is None:
        return cv2.multiply(shading, reflectance3, dtype=cv2.CV_8U)
    return cv2.add(cv2.multiply(shading, reflectance3), noise, dtype=cv2.CV_8U)
