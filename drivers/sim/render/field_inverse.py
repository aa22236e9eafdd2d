"""Backward sampling maps from forward displacement fields (drivers/sim/render/field_grid.py: the
field convention).

Rendering needs the inverse of a forward field u: for each output pixel y the reference
position x with x + u(x) = y, found by the fixed-point iteration x <- y - u(x), which
converges for smooth fields whose gradient is well below 1 (the error shrinks by about
|grad u| per iteration).

``BackwardMapper`` is the fast inversion for fields at any grid resolution: it iterates on a
grid of cells at least ``MIN_CELL_PX`` wide (the field's own grid if coarse enough, else the
field area-averaged onto one), upsamples that solution bilinearly to every pixel, and ends
with one iteration at full resolution against the field upsampled to every pixel
(``GridUpsampler``, extrapolated linearly ``MARGIN_PX`` beyond the image). That last step
shrinks the coarse solution's error by |grad u|, so the map is the inverse of the upsampled
field to within a few thousandths of a px for fields of up to 3 px with features 15 px wide,
at any input resolution (tests/drivers/test_gel_renderer.py checks it against a slow
reference). The ground truth of a rendered coarse field is therefore its upsampled field.
The iterations sample u with ``cv2.remap`` (bilinear; positions quantised to 1/32 of a grid
step), whose error is below |change of u across a step| / 64.

``backward_map`` is the plain full-resolution iteration (about 3 ms at 320 x 240), used by
the exact spline renderer (drivers/sim/render/marker_images.py).
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from drivers.sim.render.field_grid import GridUpsampler, check_field, pad_linear

MIN_CELL_PX = 4.0
"""Smallest cell (px) of the grid the fast inversion iterates on."""

ITERATIONS = 6
"""Fixed-point iterations on that grid."""

MARGIN_PX = 8
"""How far beyond the image the field is extrapolated linearly for the last iteration (px);
a map that reaches further sees the field at the margin's edge."""

_RINGS = 2  # extrapolated rings around the coarse grid for its iteration


class _GridInverter:
    """The fixed-point iteration on one grid of (h, w) nodes covering the image: backward
    displacement b (px) at the nodes, with b = -u(node + b). It runs in grid steps (px / cell
    size) on the grid padded by linear extrapolation."""

    def __init__(self, grid_hw: tuple[int, int], image_hw: tuple[int, int]) -> None:
        h, w = grid_hw
        self._cell = (image_hw[1] / w, image_hw[0] / h, 0.0, 0.0)
        self._per_cell = (w / image_hw[1], h / image_hw[0], 0.0, 0.0)
        ys, xs = np.mgrid[_RINGS : _RINGS + h, _RINGS : _RINGS + w].astype(np.float32)
        self._nodes = np.stack([xs, ys], axis=2)  # node positions in the padded grid

    def __call__(self, field: np.ndarray) -> np.ndarray:
        minus_u = pad_linear(cv2.multiply(field, self._per_cell, scale=-1.0), _RINGS)
        back = minus_u[_RINGS:-_RINGS, _RINGS:-_RINGS]
        for _ in range(ITERATIONS):
            at = cv2.add(self._nodes, back)
            back = cv2.remap(minus_u, at, None, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        return cv2.multiply(back, self._cell)


class BackwardMapper:
    """``mapper(u)`` -> the backward map (H, W, 2) float32 px: the reference position (x, y)
    each output pixel shows, for a forward field u (h, w, 2) px at any resolution with the
    image's aspect (see the module docstring). Tables per resolution are built on first use."""

    def __init__(self, image_hw: tuple[int, int]) -> None:
        self.image_hw = image_hw
        height, width = image_hw
        ys, xs = np.mgrid[0:height, 0:width].astype(np.float32)
        self._pixels = np.stack([xs, ys], axis=2)
        self._pixels_in_margin = self._pixels + np.float32(MARGIN_PX)
        self._plans: dict[tuple[int, int], tuple] = {}

    def __call__(self, displacement_px: np.ndarray) -> np.ndarray:
        field = check_field(displacement_px, self.image_hw)
        solve_hw, invert, upsample_solution, upsample_field = self._plan(field.shape[:2])
        coarse = field
        if solve_hw != field.shape[:2]:
            coarse = cv2.resize(field, solve_hw[::-1], interpolation=cv2.INTER_AREA)
        first = cv2.add(self._pixels_in_margin, upsample_solution(invert(coarse)))
        u_at = cv2.remap(
            upsample_field(field), first, None, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE
        )
        return cv2.subtract(self._pixels, u_at)

    def _plan(self, grid_hw: tuple[int, int]) -> tuple:
        plan = self._plans.get(grid_hw)
        if plan is None:
            h, w = grid_hw
            k = max(1, math.ceil(MIN_CELL_PX * w / self.image_hw[1] - 1e-9))
            solve_hw = (max(2, round(h / k)), max(2, round(w / k)))
            plan = (
                solve_hw,
                _GridInverter(solve_hw, self.image_hw),
                GridUpsampler(solve_hw, self.image_hw),
                GridUpsampler(grid_hw, self.image_hw, MARGIN_PX),
            )
            self._plans[grid_hw] = plan
        return plan


def backward_map(displacement_px: np.ndarray, iterations: int = 6) -> tuple[np.ndarray, np.ndarray]:
    """Exact full-resolution inversion: sampling maps (map_x, map_y) float32 (H, W) such that
    image(y) = reference(map(y)) for the forward field u (H, W, 2) px, by the fixed-point
    iteration on every pixel, holding u constant beyond the image. Sampling u itself with
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
