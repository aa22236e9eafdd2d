"""Synthetic marker-gel images warped by known displacement fields.

A stand-in for a visuotactile camera when the exact displacement must be known: the gel
carries dark printed markers on a lattice and a fine speckle texture; both move with the gel.
The coloured LED lighting is fixed to the camera, so it does not move: each colour channel
is a static shading times the moving gel pattern.

A displacement field here is *forward*: ``u[row, col]`` (px, [..., 0] along x, [..., 1] along
y) says where the gel point seen at pixel (col, row) in the reference moves to. That is what
optical flow from the reference to the current image measures. ``render`` inverts it to the
backward sampling map by fixed-point iteration and resamples the reference gel pattern.
"""

from __future__ import annotations

import cv2
import numpy as np
from scipy.ndimage import map_coordinates, spline_filter

# Static shading of the B, G, R channels: a base level and a gradient direction (the LEDs'
# positions), in grey levels.
_LIGHT_BASE = (150.0, 170.0, 160.0)
_LIGHT_GRADIENT = ((25.0, 0.0), (-15.0, 20.0), (-10.0, -20.0))


class MarkerImageRenderer:
    """Renders (H, W, 3) BGR uint8 images of a marker gel, warped by forward fields.

    ``pitch_px``: marker lattice pitch (``None``: a gel without printed markers, texture
    only, as the DIGIT's); ``dot_radius_px``: marker radius; ``jitter_px``:
    random offset of each marker from its lattice site; ``texture_grey``: amplitude of the
    gel's speckle texture. ``rng`` seeds the marker jitter and the texture.
    """

    def __init__(
        self,
        width_px: int = 320,
        height_px: int = 240,
        pitch_px: float | None = 31.5,
        dot_radius_px: float = 4.5,
        jitter_px: float = 1.5,
        texture_grey: float = 12.0,
        rng: np.random.Generator | None = None,
    ) -> None:
        rng = np.random.default_rng(0) if rng is None else rng
        self.shape_hw = (height_px, width_px)
        if pitch_px is None:
            self.marker_centres_px = np.empty((0, 2))
        else:
            cols = np.arange(pitch_px / 2, width_px, pitch_px)
            rows = np.arange(pitch_px / 2, height_px, pitch_px)
            cx, cy = np.meshgrid(cols, rows)
            centres = np.stack([cx.ravel(), cy.ravel()], axis=1)
            self.marker_centres_px = centres + rng.uniform(-jitter_px, jitter_px, centres.shape)
        self._pattern = self._gel_pattern(dot_radius_px, texture_grey, rng)
        self._spline = spline_filter(self._pattern, order=3, mode="mirror")
        self._shading = self._lighting()

    def _gel_pattern(
        self, radius: float, texture_grey: float, rng: np.random.Generator
    ) -> np.ndarray:
        """Reflectance of the gel in the reference pose, float32 (H, W), about 1 on the gel
        and about 0.25 inside a marker (soft, anti-aliased edges one pixel wide)."""
        height, width = self.shape_hw
        ys, xs = np.mgrid[0:height, 0:width].astype(np.float32)
        darkness = np.zeros((height, width), np.float32)
        for x, y in self.marker_centres_px:
            x0, x1 = int(max(0, x - radius - 3)), int(min(width, x + radius + 4))
            y0, y1 = int(max(0, y - radius - 3)), int(min(height, y + radius + 4))
            r = np.hypot(xs[y0:y1, x0:x1] - x, ys[y0:y1, x0:x1] - y)
            np.maximum(
                darkness[y0:y1, x0:x1],
                0.5 * (1.0 - np.tanh((r - radius) / 0.7)),
                out=darkness[y0:y1, x0:x1],
            )
        noise = cv2.GaussianBlur(
            rng.standard_normal((height, width)).astype(np.float32), (0, 0), 1.5
        )
        noise *= texture_grey / (255.0 * 0.6 * max(float(noise.std()), 1e-6))
        return (1.0 + noise) * (1.0 - 0.75 * darkness)

    def _lighting(self) -> np.ndarray:
        height, width = self.shape_hw
        ys, xs = np.mgrid[0:height, 0:width].astype(np.float32)
        gx, gy = (xs - width / 2) / width, (ys - height / 2) / height
        planes = [
            base + ax * gx * 2 + ay * gy * 2 - 20.0 * (gx**2 + gy**2)
            for base, (ax, ay) in zip(_LIGHT_BASE, _LIGHT_GRADIENT, strict=True)
        ]
        return np.stack(planes, axis=2).astype(np.float32)

    def render(self, displacement_px: np.ndarray | None = None) -> np.ndarray:
        """The image after the gel moved by the forward field ``displacement_px`` (H, W, 2);
        ``None`` renders the reference."""
        pattern = self._pattern
        if displacement_px is not None:
            # Cubic-spline resampling at full float precision: cv2.remap quantises sub-pixel
            # positions to 1/32 px, which biases sub-pixel flow ground truth by up to 0.03 px.
            map_x, map_y = backward_map(displacement_px)
            pattern = map_coordinates(
                self._spline, [map_y, map_x], order=3, mode="mirror", prefilter=False
            )
        image = self._shading * pattern[:, :, None]
        return np.clip(image + 0.5, 0, 255).astype(np.uint8)


def backward_map(displacement_px: np.ndarray, iterations: int = 6) -> tuple[np.ndarray, np.ndarray]:
    """Sampling maps (map_x, map_y) float32 such that image(y) = reference(map(y)), for the
    forward field u: solves x + u(x) = y for x by fixed-point iteration x <- y - u(x)
    (converges for smooth fields whose gradient is well below 1). Sampling u itself with
    cv2.remap is precise enough: its 1/32 px position quantisation times the field's small
    gradient is far below the flow errors of interest."""
    height, width = displacement_px.shape[:2]
    ys, xs = np.mgrid[0:height, 0:width].astype(np.float32)
    u = displacement_px.astype(np.float32)
    map_x, map_y = xs - u[..., 0], ys - u[..., 1]
    for _ in range(iterations):
        u_at = cv2.remap(u, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        map_x, map_y = xs - u_at[..., 0], ys - u_at[..., 1]
    return map_x, map_y


def smooth_random_field(
    shape_hw: tuple[int, int], amplitude_px: float, rng: np.random.Generator, n_bumps: int = 4
) -> np.ndarray:
    """A smooth random forward field (H, W, 2) in px whose largest magnitude is
    ``amplitude_px``: an affine part plus a few Gaussian bumps of 40-120 px width."""
    height, width = shape_hw
    ys, xs = np.mgrid[0:height, 0:width].astype(np.float64)
    gx, gy = (xs - width / 2) / width, (ys - height / 2) / height
    field = np.zeros((height, width, 2))
    field[..., 0] = rng.normal() + rng.normal() * gx + rng.normal() * gy
    field[..., 1] = rng.normal() + rng.normal() * gx + rng.normal() * gy
    for _ in range(n_bumps):
        cx, cy = rng.uniform(0, width), rng.uniform(0, height)
        sigma = rng.uniform(40, 120)
        bump = np.exp(-((xs - cx) ** 2 + (ys - cy) ** 2) / (2 * sigma**2))
        field[..., 0] += rng.normal() * 2 * bump
        field[..., 1] += rng.normal() * 2 * bump
    peak = np.hypot(field[..., 0], field[..., 1]).max()
    return (field * (amplitude_px / peak)).astype(np.float32)


def area_mean_field(displacement_px: np.ndarray, rows: int, cols: int) -> np.ndarray:
    """Ground truth on the grid: the area mean of a dense field over each grid cell,
    (rows, cols, 2) px, matching the estimator's pooling."""
    return cv2.resize(
        displacement_px.astype(np.float32), (cols, rows), interpolation=cv2.INTER_AREA
    ).astype(np.float64)
