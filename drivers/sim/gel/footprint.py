"""Where a grasped object touches the gel: the physics grid, the contact footprint and its gap.

The physics grid is made of square cells of ``profile.cell_m`` centred on S's origin, the
image's centre. It covers the camera's view (``width_px / cell_px`` x ``height_px /
cell_px`` cells) and, where the gel is larger than the view, the rest of the gel, with the
same number of cells on either side so the view is a centred block.

A ``Footprint`` is the object's face placed on the gel at an in-plane offset and angle:
* ``mask``: cells where the object's face and the gel overlap;
* ``sag_m``: the face's height above the plane that first touches the flat gel (the
  cylinder's curvature for a round peg, the dome's for a domed gel), so the gap closure at a
  cell is ``indentation(x, y) - sag_m``;
* ``edge_weight``: ``1 - exp(-d / edge_softening_m)``, with ``d`` the distance to the
  nearest edge of the overlap. It is the half-plane solution of the thin-layer equation
  ``(1 - l^2 laplacian) p = k delta`` with ``p = 0`` on a free edge (docs/SIMULATION.md):
  a bonded, nearly incompressible layer cannot carry pressure at an edge where it can bulge.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from drivers.sim.gel.profile import GelProfile, ObjectShape


@dataclass(frozen=True)
class PhysicsGrid:
    """Cell centres ``x_m``, ``y_m`` (rows, cols) in S, m; ``view`` the slices of the cells
    the camera sees."""

    x_m: np.ndarray
    y_m: np.ndarray
    cell_m: float
    view: tuple[slice, slice]

    @property
    def shape(self) -> tuple[int, int]:
        return self.x_m.shape

    @classmethod
    def for_profile(cls, profile: GelProfile) -> PhysicsGrid:
        cell = profile.cell_m
        view_cols = profile.width_px // profile.cell_px
        view_rows = profile.height_px // profile.cell_px
        pad_cols = max(0, math.ceil((profile.gel_width_m / cell - view_cols) / 2))
        pad_rows = max(0, math.ceil((profile.gel_height_m / cell - view_rows) / 2))
        cols, rows = view_cols + 2 * pad_cols, view_rows + 2 * pad_rows
        xs = (np.arange(cols) - (cols - 1) / 2) * cell
        ys = (np.arange(rows) - (rows - 1) / 2) * cell
        x_m, y_m = np.meshgrid(xs, ys)
        view = (slice(pad_rows, pad_rows + view_rows), slice(pad_cols, pad_cols + view_cols))
        return cls(x_m, y_m, cell, view)


@dataclass(frozen=True)
class Footprint:
    """The object's face on the gel (see the module docstring); arrays are (rows, cols)."""

    mask: np.ndarray
    sag_m: np.ndarray
    edge_weight: np.ndarray


def place_object(
    grid: PhysicsGrid,
    profile: GelProfile,
    shape: ObjectShape,
    offset_m: tuple[float, float] = (0.0, 0.0),
    angle_rad: float = 0.0,
) -> Footprint:
    """The footprint of ``shape`` whose centre sits at ``offset_m`` (x, y in S, m) and whose
    axis is turned by ``angle_rad`` about S's z from its nominal direction."""
    half_w, half_h = profile.gel_width_m / 2, profile.gel_height_m / 2
    distance = np.minimum(half_w - np.abs(grid.x_m), half_h - np.abs(grid.y_m))
    sag = np.zeros(grid.shape)
    if profile.dome_radius_m is not None:
        sag += (grid.x_m**2 + grid.y_m**2) / (2 * profile.dome_radius_m)
    if shape.kind != "plate":
        # Coordinate across the peg's axis, in the peg's own frame.
        dx, dy = grid.x_m - offset_m[0], grid.y_m - offset_m[1]
        cos, sin = math.cos(angle_rad), math.sin(angle_rad)
        across = dx * cos + dy * sin if shape.axis == "y" else -dx * sin + dy * cos
        radius = shape.width_m / 2
        distance = np.minimum(distance, radius - np.abs(across))
        if shape.kind == "round_peg":
            inside = np.minimum(np.abs(across), radius)
            sag += radius - np.sqrt(radius**2 - inside**2)
    mask = distance > 0
    if profile.edge_softening_m > 0:
        weight = -np.expm1(-np.clip(distance, 0.0, None) / profile.edge_softening_m)
    else:
        weight = mask.astype(float)
    weight = np.where(mask, weight, 0.0)
    return Footprint(mask=mask, sag_m=sag, edge_weight=weight)
