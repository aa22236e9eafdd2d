"""What every phase's state has: its present sub-stage and the rule counters of it."""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from typing import Generic, Protocol, TypeVar

S = TypeVar("S", bound=Enum)


class PhaseState(Protocol):
    """A phase's state, as the machine sees it: the present sub-stage."""

    @property
    def stage(self) -> Enum: ...


@dataclass
class Staged(Generic[S]):
    """A phase in sub-stage ``stage`` since ``since_t_s`` (s; or since a condition began to
    hold), with ``count`` successive new estimates satisfying the sub-stage's rule."""

    stage: S
    since_t_s: float
    count: int = 0

    def next(self, stage: S, t_s: float) -> None:
        """Begin sub-stage ``stage`` at ``t_s``: its timer from now, its count from zero."""
        self.stage, self.since_t_s, self.count = stage, t_s, 0
