"""The press-and-roll scene: a ball pressed into the gel with a rising force, then rolled.

It stands in for the simplest real test of a tilt estimate (a ball pressed on a GelSight
and rolled by hand) and models no more than that needs: the gel (``GelModel``) under a rigid
sphere, the normal force and the ball's roll over time; no arm, no dynamics, no friction
load (the hand pushes through the ball's centre).

Rolling a ball by a small angle moves its contact patch, and with it the centre of pressure;
on a gel the same patch shift is what a tilt torque does to a sphere held in place (the
normal contact's approach ``d0 + a y + b x`` on the sphere's paraboloid sag is the sag
shifted by ``(b R, a R)``). The scene therefore rolls the ball by the tilt torque that puts
the centre of pressure at ``e(t)`` from the ball's rest point: ``tau_x = F e_y``,
``tau_y = -F e_x`` (the wrench the gel exerts on the ball, frame S), and the truth is the
model's carried wrench about S's origin.

The program (``press_roll_program``), at the camera's frame rate:

1. ``open``: no contact (the zeroing reference);
2. ``press``: the force rises from zero to ``force_n`` (raised cosine), the ball centred;
3. ``roll``: the centre of pressure swings to +-``roll_m`` and back along x, then along y
   (``roll_cycles`` full swings each), at constant force;
4. ``press_rolled``: rolled to +``roll_m`` along x and y at once, the force rises to
   ``harder`` times ``force_n`` and back: a tilt that stays while the press changes, which a
   tilt estimate must follow without a jump.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from core.config import Config, config_dataclass, number
from drivers.sim.gel.footprint import Footprint
from drivers.sim.gel.model import GelModel, GelState, Wrench
from drivers.sim.gel.profile import GelProfile, ObjectShape

PHASES = ("open", "press", "roll", "press_rolled")


@config_dataclass
class PressRollConfig(Config):
    """The ball and its program: radius m, forces N, roll (centre-of-pressure excursion) m,
    frame counts per phase at ``rate_hz``."""

    ball_radius_m: float = number(1e-3, 0.1, default=0.008)
    force_n: float = number(1e-3, 100.0, default=4.0)
    harder: float = number(1.0, 10.0, default=2.0)
    roll_m: float = number(0.0, 0.01, default=0.0008)
    roll_cycles: int = number(1, 100, default=2)
    open_frames: int = number(1, 100000, default=10)
    press_frames: int = number(1, 100000, default=40)
    roll_frames: int = number(1, 100000, default=40)
    press_rolled_frames: int = number(1, 100000, default=40)
    rate_hz: float = number(1.0, 1000.0, default=25.0)


@dataclass(frozen=True)
class PressRollStep:
    """One frame of the program: time s, phase, normal force N, centre-of-pressure
    excursion (x, y) m."""

    t_s: float
    phase: str
    force_n: float
    roll_m: tuple[float, float]

    @property
    def wrench(self) -> Wrench:
        """The tilt torques that put the centre of pressure at ``roll_m`` (N*m, frame S)."""
        return Wrench(tau_x=self.force_n * self.roll_m[1], tau_y=-self.force_n * self.roll_m[0])


def _rise(n: int) -> np.ndarray:
    """n samples of a raised cosine from 0 (exclusive) to 1 (inclusive)."""
    return 0.5 - 0.5 * np.cos(math.pi * np.arange(1, n + 1) / n)


def press_roll_program(config: PressRollConfig) -> list[PressRollStep]:
    """The frames of the program in the module docstring."""
    force, roll = config.force_n, config.roll_m
    rows: list[tuple[str, float, float, float]] = []
    rows += [("open", 0.0, 0.0, 0.0)] * config.open_frames
    rows += [("press", force * a, 0.0, 0.0) for a in _rise(config.press_frames)]
    for axis in (0, 1):
        phase = 2 * math.pi * config.roll_cycles * np.arange(1, config.roll_frames + 1)
        swing = roll * np.sin(phase / config.roll_frames)
        rows += [("roll", force, s if axis == 0 else 0.0, s if axis == 1 else 0.0) for s in swing]
    up_down = np.sin(
        math.pi * np.arange(1, config.press_rolled_frames + 1) / config.press_rolled_frames
    )
    rows += [("press_rolled", force * (1 + (config.harder - 1) * a), roll, roll) for a in up_down]
    return [
        PressRollStep(i / config.rate_hz, phase, f, (ex, ey))
        for i, (phase, f, ex, ey) in enumerate(rows)
    ]


def ball_footprint(
    model: GelModel, radius_m: float, offset_m: tuple[float, float] = (0.0, 0.0)
) -> Footprint:
    """A sphere of ``radius_m`` whose lowest point touches the gel at ``offset_m`` (m, S):
    the sag is the sphere's height above that point, ``R - sqrt(R^2 - rho^2)``, the face
    ends at ``rho = R``, and the edge weight follows the gel's free edges and that rim as
    ``drivers.sim.gel.footprint.place_object`` does for its shapes."""
    grid, profile = model.grid, model.profile
    rho = np.hypot(grid.x_m - offset_m[0], grid.y_m - offset_m[1])
    inside = np.minimum(rho, radius_m)
    sag = radius_m - np.sqrt(radius_m**2 - inside**2)
    if profile.dome_radius_m is not None:
        sag += (grid.x_m**2 + grid.y_m**2) / (2 * profile.dome_radius_m)
    half_w, half_h = profile.gel_width_m / 2, profile.gel_height_m / 2
    distance = np.minimum.reduce(
        [half_w - np.abs(grid.x_m), half_h - np.abs(grid.y_m), radius_m - rho]
    )
    mask = distance > 0
    if profile.edge_softening_m > 0:
        weight = -np.expm1(-np.clip(distance, 0.0, None) / profile.edge_softening_m)
    else:
        weight = mask.astype(float)
    return Footprint(mask=mask, sag_m=sag, edge_weight=np.where(mask, weight, 0.0))


class BallGelModel(GelModel):
    """``GelModel`` with a rigid ball of ``radius_m`` as the object (``footprint`` places
    the ball; the offset moves it, the angle is irrelevant to a sphere)."""

    def __init__(self, profile: GelProfile, radius_m: float) -> None:
        # The base class's shape is not used: ``footprint`` below replaces its placement.
        super().__init__(profile, ObjectShape("round_peg", 2 * radius_m, "y"))
        self.radius_m = radius_m

    def footprint(
        self, offset_m: tuple[float, float] = (0.0, 0.0), angle_rad: float = 0.0
    ) -> Footprint:
        return ball_footprint(self, self.radius_m, offset_m)


def press_roll_states(model: GelModel, program: list[PressRollStep]) -> list[GelState]:
    """The gel's state at each step of ``program`` (each solve warm-started from the last)."""
    states: list[GelState] = []
    previous: GelState | None = None
    for step in program:
        previous = model.solve(step.force_n, step.wrench, start=previous)
        states.append(previous)
    return states
