"""``/tactile/field``'s grid, encoded in parts (``foxglove_types.grid_bytes``), is the same
message, byte for byte, as the whole ``foxglove.Grid`` encoded at once."""

from __future__ import annotations

import numpy as np
import pytest
from foxglove.messages import (
    Grid,
    PackedElementField,
    PackedElementFieldNumericType,
    Pose,
    Quaternion,
    Vector2,
    Vector3,
)

from controller.episode.foxglove_types import GRID_FIELDS, grid_bytes, timestamp
from controller.tactile.field import VectorField


def _whole(t_s: float, field: VectorField, offset_ns: int) -> bytes:
    dx_mm, dy_mm = field.spacing_mm
    cells = np.stack([field.u_mm, field.v_mm, field.divergence()], axis=-1).astype("<f4")
    cols = field.shape[1]
    return Grid(
        timestamp=timestamp(t_s, offset_ns),
        frame_id="S",
        pose=Pose(
            position=Vector3(
                x=(float(field.x_mm[0]) - dx_mm / 2) * 1e-3,
                y=(float(field.y_mm[0]) - dy_mm / 2) * 1e-3,
                z=0.0,
            ),
            orientation=Quaternion(x=0.0, y=0.0, z=0.0, w=1.0),
        ),
        column_count=cols,
        cell_size=Vector2(x=dx_mm * 1e-3, y=dy_mm * 1e-3),
        row_stride=cols * 12,
        cell_stride=12,
        fields=[
            PackedElementField(name=name, offset=4 * i, type=PackedElementFieldNumericType.Float32)
            for i, name in enumerate(GRID_FIELDS)
        ],
        data=cells.tobytes(),
    ).encode()


@pytest.mark.parametrize("shape", [(12, 16), (3, 3), (7, 40)])
@pytest.mark.parametrize("t_s", [0.0, 1.23456789, 812.5])
def test_the_grid_in_parts_is_the_whole_grid(shape, t_s):
    rng = np.random.default_rng(sum(shape))
    rows, cols = shape
    field = VectorField(
        np.linspace(-7.5, 7.5, cols) + 0.1,
        np.linspace(-5.5, 5.5, rows) - 0.2,
        rng.normal(0.0, 0.3, shape),
        rng.normal(0.0, 0.3, shape),
    )
    for offset_ns in (0, 1_764_690_000_123_456_789):
        assert grid_bytes(t_s, field, offset_ns) == _whole(t_s, field, offset_ns)
