"""The press-tilt-release program: what a hand does to a gripped object to test a tilt estimate.

The object (any ``GelModel`` shape) sits on the gel; the program only sets the grip's normal
force and the tilt torques the gel exerts on it (frame S, N*m), one frame per camera frame:

1. ``open``: no contact (grip 0 N; the zeroing reference and the quiet check);
2. ``press``: the grip rises from 0 to ``grip_n`` (raised cosine);
3. ``tilt_x``: the torque about x swings to +``tilt_nm`` and back (a raised-cosine bump of
   ``tilt_frames`` frames), then to -``tilt_nm`` and back;
4. ``tilt_y``: the same about y;
5. ``release``: the grip falls back to 0 (raised cosine);
6. ``open`` again for ``open_frames`` frames.

A segment is a (phase, sign) pair: ``tilt_x+``, ``tilt_x-``, ``tilt_y+``, ``tilt_y-``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from core.config import Config, config_dataclass, number
from drivers.sim.gel.model import GelModel, GelState, Wrench

PHASES = ("open", "press", "tilt_x", "tilt_y", "release")


@config_dataclass
class PressTiltConfig(Config):
    """The program: grip N, tilt torque N*m, frame counts per phase at ``rate_hz``."""

    grip_n: float = number(0.1, 100.0, default=10.0)
    tilt_nm: float = number(0.0, 1.0, default=0.012)
    open_frames: int = number(1, 100000, default=8)
    press_frames: int = number(1, 100000, default=12)
    tilt_frames: int = number(2, 100000, default=15)
    release_frames: int = number(1, 100000, default=10)
    rate_hz: float = number(1.0, 1000.0, default=25.0)


@dataclass(frozen=True)
class PressTiltStep:
    """One frame of the program: time s, phase, grip N, tilt torques N*m (frame S)."""

    t_s: float
    phase: str
    grip_n: float
    tau_x_nm: float
    tau_y_nm: float

    @property
    def segment(self) -> str:
        """``tilt_x+`` etc. in a tilt phase (the sign of the phase's torque), else the phase."""
        if self.phase not in ("tilt_x", "tilt_y"):
            return self.phase
        torque = self.tau_x_nm if self.phase == "tilt_x" else self.tau_y_nm
        return self.phase + ("+" if torque >= 0 else "-")


def _rise(n: int) -> np.ndarray:
    """n samples of a raised cosine from 0 (exclusive) to 1 (inclusive)."""
    return 0.5 - 0.5 * np.cos(math.pi * np.arange(1, n + 1) / n)


def _bump(n: int) -> np.ndarray:
    """n samples of one raised-cosine period, 0 -> 1 -> 0, both ends excluded."""
    return 0.5 - 0.5 * np.cos(2 * math.pi * np.arange(1, n + 1) / (n + 1))


def press_tilt_program(config: PressTiltConfig) -> list[PressTiltStep]:
    """The frames of the program in the module docstring."""
    grip, tilt = config.grip_n, config.tilt_nm
    rows: list[tuple[str, float, float, float]] = [("open", 0.0, 0.0, 0.0)] * config.open_frames
    rows += [("press", grip * a, 0.0, 0.0) for a in _rise(config.press_frames)]
    for phase in ("tilt_x", "tilt_y"):
        for sign in (1.0, -1.0):
            for a in _bump(config.tilt_frames):
                torque = float(sign * tilt * a)
                rows.append(
                    (
                        phase,
                        grip,
                        torque if phase == "tilt_x" else 0.0,
                        torque if phase == "tilt_y" else 0.0,
                    )
                )
    rows += [("release", grip * (1.0 - a), 0.0, 0.0) for a in _rise(config.release_frames)]
    rows += [("open", 0.0, 0.0, 0.0)] * config.open_frames
    return [
        PressTiltStep(i / config.rate_hz, phase, float(g), tx, ty)
        for i, (phase, g, tx, ty) in enumerate(rows)
    ]


def press_tilt_states(model: GelModel, program: list[PressTiltStep]) -> list[GelState]:
    """The gel's state at each step of ``program`` (each solve warm-started from the last)."""
    states: list[GelState] = []
    previous: GelState | None = None
    for step in program:
        wrench = Wrench(tau_x=step.tau_x_nm, tau_y=step.tau_y_nm)
        previous = model.solve(step.grip_n, wrench, start=previous)
        states.append(previous)
    return states
