"""Analytic test fields on the default 16 x 12 grid (frame S, mm)."""

from __future__ import annotations

import numpy as np

from controller.tactile.field import grid_axes_mm

X_MM, Y_MM = grid_axes_mm(320, 240, 16, 12, 0.0634)
GRID_X, GRID_Y = np.meshgrid(X_MM, Y_MM)


def charge_on(
    gx: np.ndarray, gy: np.ndarray, cx: float, cy: float, q: float, width: float = 1.0
) -> tuple[np.ndarray, np.ndarray]:
    """Field of a Gaussian 'charge' of total divergence ``q`` (mm^2) centred at (cx, cy) mm:
    v = q (x - c) / (2 pi r^2) (1 - exp(-r^2 / 2 w^2)), whose divergence is the Gaussian
    q exp(-r^2 / 2 w^2) / (2 pi w^2). Positive q spreads outward, negative q draws inward."""
    dx, dy = gx - cx, gy - cy
    r2 = dx**2 + dy**2
    safe = np.where(r2 > 0, r2, 1.0)
    radial = np.where(r2 > 0, -np.expm1(-r2 / (2 * width**2)) / safe, 1 / (2 * width**2))
    k = q / (2 * np.pi) * radial
    return k * dx, k * dy


def source(cx: float, cy: float, q: float, width: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """``charge_on`` on the default grid."""
    return charge_on(GRID_X, GRID_Y, cx, cy, q, width)


def charge_pair(axis: str, separation: float, q: float = 0.05) -> tuple[np.ndarray, np.ndarray]:
    """A charge +q at +separation/2 and -q at -separation/2 along ``axis`` ('x' or 'y')."""
    h = separation / 2
    (px, py), (nx, ny) = ((h, 0), (-h, 0)) if axis == "x" else ((0, h), (0, -h))
    pu, pv = source(px, py, q)
    nu, nv = source(nx, ny, -q)
    return pu + nu, pv + nv
