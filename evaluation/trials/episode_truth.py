"""The simulator's truth in a trial's episode (``/sim/truth``, ``/sim/tf``), written by the
trial tools, never by the controller: a loop observer that, each tick, queues the truth rows
the scene appended since the previous tick (controller/episode/topics.py). It reads the
world only (never ``sync``, so recording does not change the run)."""

from __future__ import annotations

from typing import Any

import numpy as np

from controller.episode import topics
from controller.episode.foxglove_types import transforms_bytes
from controller.episode.recorder import finite_or_none
from controller.episode.writer import EpisodeWriter, json_bytes
from controller.loop import TickRecord
from drivers.sim.scenes.insertion.truth import COLUMNS


def truth_json(row: np.ndarray) -> bytes:
    out: dict[str, Any] = {}
    start = 0
    for name, width in COLUMNS.items():
        values = [finite_or_none(v) for v in row[start : start + width]]
        out[name] = values[0] if width == 1 else values
        start += width
    return json_bytes(out)


def _truth_tf(item: tuple[np.ndarray, Any]) -> bytes:
    row, hole = item
    named = dict(zip(COLUMNS, np.split(row, np.cumsum(list(COLUMNS.values()))[:-1]), strict=True))
    w, x, y, z = named["plug_quat_b"]
    half = hole.yaw_rad / 2.0
    return transforms_bytes(
        float(named["t_s"][0]),
        [
            ("B", "plug", named["tip_xyz_b"], np.array([x, y, z, w])),
            (
                "B",
                "H",
                np.array([hole.x_m, hole.y_m, hole.z_m]),
                np.array([0.0, 0.0, np.sin(half), np.cos(half)]),
            ),
        ],
    )


class SimTruthLogger:
    """Queues the world's new truth rows into ``writer`` each tick; ``attach(world)`` (the
    run path's ``prepare`` hook) gives it the world once built; ``drain()`` queues what is
    left at the end (after the trial's final ``sync``)."""

    def __init__(self, writer: EpisodeWriter) -> None:
        self.writer = writer
        self.world: Any = None
        self._seen = 0

    def attach(self, world: Any) -> None:
        self.world = world

    def __call__(self, tick: TickRecord) -> None:
        del tick
        self.drain()

    def drain(self) -> None:
        if self.world is None:
            return
        truth = self.world.truth
        rows = truth.rows_since(self._seen)
        self._seen += len(rows)
        for row in rows:
            t_s = float(row[0])
            self.writer.log(topics.SIM_TRUTH, t_s, truth_json, row)
            self.writer.log(topics.SIM_TF, t_s, _truth_tf, (row, truth.hole))
