"""Foxglove's well-known messages (``foxglove-sdk``'s classes, protobuf-encoded): the
tactile image, the displacement field as a grid, and frame transforms. Each ``*_bytes``
function runs on the episode writer's thread."""

from __future__ import annotations

import functools
from collections.abc import Sequence
from typing import Any

import cv2
import numpy as np
from foxglove.messages import (
    CompressedImage,
    FrameTransform,
    FrameTransforms,
    Grid,
    PackedElementField,
    PackedElementFieldNumericType,
    Pose,
    Quaternion,
    Timestamp,
    Vector2,
    Vector3,
)

from controller.tactile.field import VectorField

_MESSAGES: dict[str, Any] = {
    "foxglove.CompressedImage": CompressedImage,
    "foxglove.Grid": Grid,
    "foxglove.FrameTransforms": FrameTransforms,
}

GRID_FIELDS = ("u_mm", "v_mm", "div")
"""The ``/tactile/field`` grid's float32 fields, in cell order."""


def schema(name: str) -> Any:
    """The protobuf schema (a FileDescriptorSet) of the well-known message ``name``."""
    return _MESSAGES[name].get_schema()


def timestamp(t_s: float, offset_ns: int = 0) -> Timestamp:
    """``t_s`` (s on the loop's clock) plus ``offset_ns`` (the episode's offset to the wall
    clock, ``EpisodeWriter.offset_ns``; the result >= 0) as a protobuf timestamp: on the
    clock of the log times, so a viewer lines the message up with them."""
    sec, nsec = divmod(round(t_s * 1e9) + offset_ns, 1_000_000_000)
    return Timestamp(sec=sec, nsec=nsec)


def loop_time_s(stamp: Any, offset_ns: int = 0) -> float:
    """A protobuf timestamp written by ``timestamp`` back on the loop's clock, s
    (``offset_ns``: the episode's, ``Episode.offset_ns``)."""
    return (stamp.seconds * 1_000_000_000 + stamp.nanos - offset_ns) / 1e9


def encode_image(image: np.ndarray, image_format: str, jpeg_quality: int) -> bytes:
    """``image`` (uint8 BGR, BGRA or grey) as ``image_format`` ('jpeg' or 'png') bytes;
    PNG is lossless (BGRA keeps its alpha), JPEG drops an alpha channel. The writer's
    encoder, and the one an episode gives the camera (``compress_frames``) for its JPEGs."""
    if image_format == "png":
        ok, data = cv2.imencode(".png", image, [cv2.IMWRITE_PNG_COMPRESSION, 1])
    else:
        if image.ndim == 3 and image.shape[2] == 4:
            image = cv2.cvtColor(image, cv2.COLOR_BGRA2BGR)
        ok, data = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, jpeg_quality])
    if not ok:
        raise ValueError(f"tactile image of shape {image.shape}: OpenCV cannot encode it")
    return data.tobytes()


def image_bytes(
    capture_t_s: float,
    image: np.ndarray | bytes,
    image_format: str,
    jpeg_quality: int,
    offset_ns: int = 0,
) -> bytes:
    """A ``foxglove.CompressedImage`` of ``image`` captured at ``capture_t_s`` (loop's clock;
    stamped plus ``offset_ns``) in frame S: ``image`` encoded as ``image_format``, or
    ``image`` itself when it is bytes already in that format (a camera's JPEG)."""
    data = image if isinstance(image, bytes) else encode_image(image, image_format, jpeg_quality)
    return CompressedImage(
        timestamp=timestamp(capture_t_s, offset_ns), frame_id="S", data=data, format=image_format
    ).encode()


def grid_bytes(capture_t_s: float, field: VectorField, offset_ns: int = 0) -> bytes:
    """A ``foxglove.Grid`` of ``field`` (u, v in mm and the divergence) in frame S: cells of
    the field's spacing (m), the corner at the first cell's outer corner.

    Encoded in three parts, which protobuf reads as one message: the timestamp (the first
    field), the grid's layout (``grid_layout``: the same for every frame of a run) and the
    cells (the last field); the same bytes as the whole ``Grid`` encoded at once."""
    dx_mm, dy_mm = field.spacing_mm
    rows, cols = field.shape
    cells = np.empty((rows, cols, len(GRID_FIELDS)), "<f4")
    cells[..., 0] = field.u_mm
    cells[..., 1] = field.v_mm
    cells[..., 2] = field.divergence()
    layout = grid_layout(cols, float(field.x_mm[0]), float(field.y_mm[0]), dx_mm, dy_mm)
    stamp = Grid(timestamp=timestamp(capture_t_s, offset_ns)).encode()
    return stamp + layout + Grid(data=cells.tobytes()).encode()


@functools.lru_cache(maxsize=8)
def grid_layout(cols: int, x0_mm: float, y0_mm: float, dx_mm: float, dy_mm: float) -> bytes:
    """The encoded ``foxglove.Grid`` fields that depend on the grid only: frame S, the pose
    of the corner (the first cell, centre ``x0_mm``, ``y0_mm``, less half a cell), ``cols``
    columns of ``dx_mm`` x ``dy_mm`` cells (m in the message) and the cells' float32
    fields (``GRID_FIELDS``)."""
    corner = Vector3(x=(x0_mm - dx_mm / 2) * 1e-3, y=(y0_mm - dy_mm / 2) * 1e-3, z=0.0)
    float32 = PackedElementFieldNumericType.Float32
    return Grid(
        frame_id="S",
        pose=Pose(position=corner, orientation=Quaternion(x=0.0, y=0.0, z=0.0, w=1.0)),
        column_count=cols,
        cell_size=Vector2(x=dx_mm * 1e-3, y=dy_mm * 1e-3),
        row_stride=cols * 4 * len(GRID_FIELDS),
        cell_stride=4 * len(GRID_FIELDS),
        fields=[
            PackedElementField(name=name, offset=4 * i, type=float32)
            for i, name in enumerate(GRID_FIELDS)
        ],
    ).encode()


Vector = Sequence[float] | np.ndarray


def transforms_bytes(
    t_s: float, frames: list[tuple[str, str, Vector, Vector]], offset_ns: int = 0
) -> bytes:
    """A ``foxglove.FrameTransforms`` at ``t_s`` (loop's clock; stamped plus ``offset_ns``):
    each (parent, child, translation m (3), quaternion (x, y, z, w))."""
    stamp = timestamp(t_s, offset_ns)
    return FrameTransforms(
        transforms=[
            FrameTransform(
                timestamp=stamp,
                parent_frame_id=parent,
                child_frame_id=child,
                translation=Vector3(x=float(p[0]), y=float(p[1]), z=float(p[2])),
                rotation=Quaternion(x=float(q[0]), y=float(q[1]), z=float(q[2]), w=float(q[3])),
            )
            for parent, child, p, q in frames
        ]
    ).encode()
