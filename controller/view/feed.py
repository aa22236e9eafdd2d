"""The live view's feed: ``ViewFeed``, an ``EpisodeWriter`` listener (on the logger
thread: the control loop never waits for the view) that builds a ``ViewSnapshot`` from the
episode's own records.

It keeps the newest frame, field and tick, and at each estimate (the sensor's frame rate)
hands one snapshot to ``offer``, which must not block (``LiveView.offer`` drops a snapshot
the view has no room for).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from controller.episode import topics
from controller.loop import TickRecord
from controller.tactile.field import VectorField
from controller.tactile.wrench import WrenchEstimate
from controller.view.snapshot import ViewSnapshot


class ViewFeed:
    """The episode writer's listener that builds ``ViewSnapshot``s (see the module doc).
    ``offer``: takes each snapshot without blocking; ``mm_per_px``: the sensor's scale."""

    def __init__(self, offer: Callable[[ViewSnapshot], Any], mm_per_px: float) -> None:
        self.offer = offer
        self.mm_per_px = mm_per_px
        self._image: np.ndarray | None = None
        self._field: VectorField | None = None
        self._tick: TickRecord | None = None

    def __call__(self, topic: topics.Topic, t_ns: int, payload: Any, data: bytes) -> None:
        del t_ns, data
        if topic is topics.TACTILE_IMAGE:
            self._image = payload[1]
            self._field = None
        elif topic is topics.TACTILE_FIELD:
            self._field = payload[1]
        elif topic is topics.LOOP_TICK:
            self._tick = payload
        elif topic is topics.TACTILE_WRENCH:
            self.offer(self._snapshot(payload[1]))

    def _snapshot(self, estimate: WrenchEstimate) -> ViewSnapshot:
        field, tick = self._field, self._tick
        teleop = tick.observation.teleop if tick is not None else None
        return ViewSnapshot(
            t_s=estimate.t_s,
            image=self._image,
            x_mm=None if field is None else field.x_mm,
            y_mm=None if field is None else field.y_mm,
            u_mm=None if field is None else field.u_mm,
            v_mm=None if field is None else field.v_mm,
            div=None if field is None else field.divergence(),
            tau=tuple(_finite(getattr(estimate, k)) for k in ("tau_x", "tau_y", "tau_z")),  # type: ignore[arg-type]
            calibrated=estimate.calibrated,
            phase=tick.phase.value if tick is not None else "starting",
            operator=bool(teleop and teleop.in_control),
            connected=bool(teleop and teleop.connected),
            deadman=bool(teleop and teleop.deadman),
            estop=bool(teleop and teleop.estop)
            or (tick is not None and tick.phase.value == "estop"),
            mm_per_px=self.mm_per_px,
        )


def _finite(value: float) -> float:
    value = float(value)
    return value if math.isfinite(value) else math.nan
