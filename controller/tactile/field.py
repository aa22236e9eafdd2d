"""Displacement fields on a regular grid in the sensor frame S, and their differential operators.

Frame S (docs/ARCHITECTURE.md): origin at the gel centre, x along image columns (right),
y along image rows (down), z = x cross y. Positions and displacements are in mm.

Arrays are indexed ``[row, col]``: axis 0 is y, axis 1 is x.

Border handling of every derivative: second-order central differences in the interior,
first-order one-sided differences on the border rows and columns (as ``numpy.gradient``
with ``edge_order=1``). The operators write into caller-owned ``out`` arrays so the
per-frame pipeline allocates nothing.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

MIN_GRID_POINTS = 3


def grid_axes_mm(
    width_px: int, height_px: int, cols: int, rows: int, mm_per_px: float
) -> tuple[np.ndarray, np.ndarray]:
    """Cell-centre coordinates (x of each column, y of each row) in mm in frame S.

    The image of ``width_px`` x ``height_px`` is cut into ``cols`` x ``rows`` equal cells; a
    cell's position is its centre, so column j sits at ``((j + 0.5) * width_px / cols -
    width_px / 2) * mm_per_px`` (the half-cell offset matters: without it the grid is shifted
    by half a cell and every torque picks up a spurious lever arm).
    """
    if cols < MIN_GRID_POINTS or rows < MIN_GRID_POINTS:
        raise ValueError(
            f"grid must be at least {MIN_GRID_POINTS}x{MIN_GRID_POINTS} cells, got {cols}x{rows}"
        )
    x = ((np.arange(cols) + 0.5) * (width_px / cols) - width_px / 2) * mm_per_px
    y = ((np.arange(rows) + 0.5) * (height_px / rows) - height_px / 2) * mm_per_px
    return x, y


@dataclass(frozen=True)
class VectorField:
    """A 2-D displacement field sampled on a regular grid in frame S.

    ``x_mm`` (cols,) and ``y_mm`` (rows,) are the cell-centre coordinates; ``u_mm`` and
    ``v_mm`` (rows, cols) the x and y displacement components, in mm.
    """

    x_mm: np.ndarray
    y_mm: np.ndarray
    u_mm: np.ndarray
    v_mm: np.ndarray

    def __post_init__(self) -> None:
        shape = (self.y_mm.size, self.x_mm.size)
        if self.u_mm.shape != shape or self.v_mm.shape != shape:
            raise ValueError(
                f"field components must have shape (rows, cols) = {shape}, "
                f"got u {self.u_mm.shape} and v {self.v_mm.shape}"
            )
        if min(shape) < MIN_GRID_POINTS:
            raise ValueError(f"field grid must be at least 3x3, got {shape}")

    @property
    def shape(self) -> tuple[int, int]:
        """(rows, cols)."""
        return self.u_mm.shape

    @property
    def spacing_mm(self) -> tuple[float, float]:
        """Grid spacing (dx, dy) in mm."""
        return float(self.x_mm[1] - self.x_mm[0]), float(self.y_mm[1] - self.y_mm[0])

    def divergence(self) -> np.ndarray:
        """du/dx + dv/dy (dimensionless), shape (rows, cols)."""
        dx, dy = self.spacing_mm
        return divergence(self.u_mm, self.v_mm, dx, dy, np.empty(self.shape), np.empty(self.shape))

    def curl(self) -> np.ndarray:
        """z-component of the curl, dv/dx - du/dy (dimensionless), shape (rows, cols)."""
        dx, dy = self.spacing_mm
        return curl(self.u_mm, self.v_mm, dx, dy, np.empty(self.shape), np.empty(self.shape))


def require_finite(name: str, *arrays: np.ndarray) -> None:
    """Raise ValueError naming ``name`` if any array holds NaN or inf.

    Checks the sum, which is non-finite exactly when an element is (short of overflow near
    1e308), so the check allocates nothing.
    """
    for array in arrays:
        if not np.isfinite(array.sum()):
            raise ValueError(f"{name} contains NaN or inf; expected finite displacements")


@functools.lru_cache(maxsize=64)
def _difference_weights(n: int, spacing: float) -> np.ndarray:
    """Per-index factors that turn raw differences into derivatives: 1/h on the two border
    samples (one-sided), 1/2h inside (central)."""
    weights = np.full(n, 0.5 / spacing)
    weights[[0, -1]] = 1.0 / spacing
    weights.flags.writeable = False
    return weights


def d_dx(f: np.ndarray, dx: float, out: np.ndarray) -> np.ndarray:
    """Derivative along x (the last axis) of ``f`` (..., rows, cols), spacing ``dx``, into
    ``out``. Stacked fields (2, rows, cols) are differentiated in one call."""
    np.subtract(f[..., 2:], f[..., :-2], out=out[..., 1:-1])
    np.subtract(f[..., 1], f[..., 0], out=out[..., 0])
    np.subtract(f[..., -1], f[..., -2], out=out[..., -1])
    out *= _difference_weights(f.shape[-1], dx)
    return out


def d_dy(f: np.ndarray, dy: float, out: np.ndarray) -> np.ndarray:
    """Derivative along y (the second-to-last axis) of ``f`` (..., rows, cols), into ``out``."""
    np.subtract(f[..., 2:, :], f[..., :-2, :], out=out[..., 1:-1, :])
    np.subtract(f[..., 1, :], f[..., 0, :], out=out[..., 0, :])
    np.subtract(f[..., -1, :], f[..., -2, :], out=out[..., -1, :])
    out *= _difference_weights(f.shape[-2], dy)[:, None]
    return out


def divergence(
    u: np.ndarray, v: np.ndarray, dx: float, dy: float, out: np.ndarray, work: np.ndarray
) -> np.ndarray:
    """du/dx + dv/dy into ``out``; ``work`` is a scratch array of the same shape."""
    d_dx(u, dx, out)
    out += d_dy(v, dy, work)
    return out


def curl(
    u: np.ndarray, v: np.ndarray, dx: float, dy: float, out: np.ndarray, work: np.ndarray
) -> np.ndarray:
    """dv/dx - du/dy (z-component of the curl) into ``out``; ``work`` is scratch."""
    d_dx(v, dx, out)
    out -= d_dy(u, dy, work)
    return out


def block_mean(array: np.ndarray, block: tuple[int, int], out: np.ndarray) -> np.ndarray:
    """Mean over blocks of ``block`` = (rows, cols) cells of a (rows, cols) array into ``out``;
    the array's sizes must be multiples of the block's. A block of (1, 1) copies."""
    rows, cols = array.shape
    k_rows, k_cols = block
    # np.mean's own steps (a sum, then a division by the count), without its per-call checks
    blocks = array.reshape(rows // k_rows, k_rows, cols // k_cols, k_cols)
    np.add.reduce(blocks, axis=(1, 3), out=out)
    return np.true_divide(out, k_rows * k_cols, out=out)
