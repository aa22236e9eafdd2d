"""The simulator's truth in a trial's episode (``/sim/truth``, ``/sim/tf``), written by the
trial tools, never by the controller: a loop observer that, each tick, queues the truth rows
the scene appended since the previous tick (controller/episode/topics.py; ``/sim/tf`` at
most every ``TF_PERIOD_S``, as ``/tf``). It reads the world only (never ``sync``, so
recording does not change the run)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from controller.episode import topics
from controller.episode.foxglove_types import transforms_bytes
from controller.episode.recorder import TF_PERIOD_S, Latch
from controller.episode.session import EpisodeRecording
from controller.episode.writer import json_bytes
from controller.loop import TickRecord
from drivers.sim.scenes.insertion.truth import COLUMNS

_SLICES = {
    name: slice(start, start + width)
    for name, width, start in zip(
        COLUMNS, COLUMNS.values(), np.cumsum([0, *COLUMNS.values()])[:-1], strict=True
    )
}
"""Each column's place in a truth row."""


def truth_json(row: np.ndarray) -> bytes:
    out: dict[str, Any] = {}
    values = row.tolist()
    for name, where in _SLICES.items():
        out[name] = values[where] if COLUMNS[name] > 1 else values[where.start]
    return json_bytes(out)


def _truth_tf(item: tuple[np.ndarray, Any, int]) -> bytes:
    row, hole, offset_ns = item
    values = row.tolist()
    w, x, y, z = values[_SLICES["plug_quat_b"]]
    half = hole.yaw_rad / 2.0
    return transforms_bytes(
        values[0],
        [
            ("B", "plug", values[_SLICES["tip_xyz_b"]], (x, y, z, w)),
            ("B", "H", (hole.x_m, hole.y_m, hole.z_m), (0.0, 0.0, math.sin(half), math.cos(half))),
        ],
        offset_ns,
    )


class SimTruthLogger:
    """Queues the world's new truth rows into ``recording``'s writer each tick;
    ``attach(world)`` (the run path's ``prepare`` hook) gives it the world once built;
    ``drain()`` queues what is left at the end (after the trial's final ``sync``)."""

    def __init__(self, recording: EpisodeRecording) -> None:
        self.recording = recording
        self.world: Any = None
        self._seen = 0
        self._tf = Latch(TF_PERIOD_S)

    def attach(self, world: Any) -> None:
        self.world = world

    def __call__(self, tick: TickRecord) -> None:
        del tick
        self.drain()

    def drain(self) -> None:
        writer = self.recording.writer
        if self.world is None or writer is None:
            return
        truth = self.world.truth
        rows = truth.rows_since(self._seen)
        self._seen += len(rows)
        for row in rows:
            t_s = float(row[0])
            writer.log(topics.SIM_TRUTH, t_s, truth_json, row)
            if self._tf.due(None, t_s):
                writer.log(topics.SIM_TF, t_s, _truth_tf, (row, truth.hole, writer.offset_ns))
