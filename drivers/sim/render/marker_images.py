"""Synthetic marker-gel images with exact sub-pixel truth, and test fields.

``MarkerImageRenderer`` is the exact mode of the gel renderer, for flow-accuracy benchmarks
and tests: the same gel and lighting as ``drivers.sim.render.gel_renderer.GelRenderer`` (the same
``rng`` gives the same reference image), warped by a full-resolution forward field
(drivers/sim/render/field_grid.py: convention) inverted on every pixel and resampled with cubic
splines at full float precision, without image effects. It takes about 20 ms a frame;
``GelRenderer`` is the fast one (1/64 px positions) with effects.
"""

from __future__ import annotations

import cv2
import numpy as np
from scipy.ndimage import map_coordinates, spline_filter

from drivers.sim.render.appearance import make_gel_pattern
from drivers.sim.render.field_inverse import backward_map
from drivers.sim.render.lighting import shade
from drivers.sim.render.realistic import RealisticLook


class MarkerImageRenderer:
    """Renders (H, W, 3) BGR uint8 images of a marker gel, warped by forward fields.

    ``pitch_px``: marker lattice pitch (``None``: a gel without printed markers, texture
    only, as the DIGIT's); ``dot_radius_px``: marker radius; ``jitter_px``:
    random offset of each marker from its lattice site; ``texture_grey``: amplitude of the
    gel's speckle texture. ``rng`` seeds the marker jitter and the texture. ``appearance``:
    the gel's look, as ``GelRenderer``'s (drivers/sim/render/appearance.py).
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
        appearance: str | RealisticLook = "speckle",
    ) -> None:
        rng = np.random.default_rng(0) if rng is None else rng
        self.shape_hw = shape_hw = (height_px, width_px)
        gel = make_gel_pattern(
            appearance, shape_hw, pitch_px, dot_radius_px, jitter_px, texture_grey, rng
        )
        self.marker_centres_px = gel.marker_centres_px
        self._pattern = gel.reflectance(np.ones(len(self.marker_centres_px), bool))
        channels = [self._pattern] if self._pattern.ndim == 2 else cv2.split(self._pattern)
        self._splines = [spline_filter(c, order=3, mode="mirror") for c in channels]
        self._shading = gel.shading

    def render(self, displacement_px: np.ndarray | None = None) -> np.ndarray:
        """The image after the gel moved by the forward field ``displacement_px`` (H, W, 2)
        px; ``None`` renders the reference."""
        pattern = self._pattern
        if displacement_px is not None:
            # Cubic-spline resampling at full float precision: cv2.remap quantises sub-pixel
            # positions to 1/32 px, which biases sub-pixel flow ground truth by up to 0.03 px.
            map_x, map_y = backward_map(displacement_px)
            channels = [
                map_coordinates(spline, [map_y, map_x], order=3, mode="mirror", prefilter=False)
                for spline in self._splines
            ]
            pattern = channels[0] if len(channels) == 1 else cv2.merge(channels)
        return shade(pattern, self._shading)


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
