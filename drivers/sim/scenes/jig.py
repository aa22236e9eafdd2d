"""The calibration-jig scene: a plate (or peg) squeezed between the live gel and a passive
one while a person twists it, and a force/torque sensor measures the twist.

What the scene models, and no more (docs/SIMULATION.md): the grip, the hand's torque
program, how much of it the live gel carries, and the gel's response (``GelModel``). No arm,
no dynamics: the loading is quasi-static.

The program (``jig_program``), per experiment (an axis and a maximum applied torque):
pulses of alternating sign, each a raised-cosine ramp up, a hold and a ramp down, then a
rest; durations and peak heights vary randomly per pulse, as a hand's do. The hand is not a
perfect single-axis actuator: small torques about the other axes (``crosstalk``) and small
in-plane forces (``stray_force_n``) ride along, varying slowly. Before the experiments the
gel is open (no contact), then the grip closes and holds still: those frames are the
zeroing reference.

Frames: the live gel carries ``gel_load_factor`` times the applied wrench (the passive gel
the rest; -1/2 for two identical gels, negative because the gel's wrench on the plate
opposes the hand's) plus the grip.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

from core.config import Config, check_number, config_dataclass, number
from drivers.sim.gel.model import GelModel, GelState, Wrench

_AXIS_COLUMN = {"x": 3, "y": 4, "z": 5}  # torque columns of a (fx, fy, fz, tx, ty, tz) row
_PROGRAM_RATE_HZ = 500.0


@config_dataclass
class JigConfig(Config):
    """``configs/scenes/calibration_jig.yaml``: timing in s, forces N, torques N*m."""

    grip_force_n: float = number(0.1, 200.0)
    gel_load_factor: float = number(-1.0, 1.0)
    tactile_rate_hz: float = number(1.0, 1000.0)
    tactile_jitter_s: float = number(0.0, 0.25)  # and at most a quarter frame period
    ft_rate_hz: float = number(1.0, 10000.0)
    ft_force_noise_n: float = number(0.0, 10.0)
    ft_torque_noise_nm: float = number(0.0, 1.0)
    open_s: float = number(0.0, 60.0)
    grasp_s: float = number(0.0, 60.0)
    settle_s: float = number(0.0, 60.0)
    ramp_min_s: float = number(0.0, 60.0)
    ramp_max_s: float = number(0.0, 60.0)
    hold_min_s: float = number(0.0, 60.0)
    hold_max_s: float = number(0.0, 60.0)
    rest_min_s: float = number(0.0, 60.0)
    rest_max_s: float = number(0.0, 60.0)
    amplitude_spread: float = number(0.0, 0.9)
    crosstalk: float = number(0.0, 1.0)
    stray_force_n: float = number(0.0, 50.0)

    def __post_init__(self) -> None:
        check_number("tactile_jitter_s", self.tactile_jitter_s, 0.0, 0.25 / self.tactile_rate_hz)
        for low, high in (
            ("ramp_min_s", "ramp_max_s"),
            ("hold_min_s", "hold_max_s"),
            ("rest_min_s", "rest_max_s"),
        ):
            check_number(high, getattr(self, high), getattr(self, low), 60.0)


@config_dataclass
class Experiment(Config):
    """Alternating torque pulses about S's ``axis`` up to ``amplitude_nm`` (N*m, applied by
    the hand), ``pulses`` of them."""

    axis: Literal["x", "y", "z"]
    amplitude_nm: float = number(0.0, 10.0)
    pulses: int = number(1, 100000)


@dataclass(frozen=True)
class Segment:
    """Where an experiment ran: [t_start_s, t_end_s)."""

    axis: str
    amplitude_nm: float
    t_start_s: float
    t_end_s: float


@dataclass(frozen=True)
class LoadProgram:
    """The applied wrench and grip over time, sampled at 500 Hz and linearly interpolated.
    ``wrench`` rows are (fx, fy, fz in N, tau_x, tau_y, tau_z in N*m) applied by the hand,
    in S; ``reference`` the still, gripped interval used for zeroing."""

    t_s: np.ndarray
    wrench: np.ndarray
    grip_n: np.ndarray
    segments: tuple[Segment, ...]
    reference: tuple[float, float]

    @property
    def duration_s(self) -> float:
        return float(self.t_s[-1])

    def applied(self, t_s: float) -> np.ndarray:
        """The applied wrench (6,) at ``t_s``, held constant beyond the program's ends (as
        ``np.interp``; one binary search for all six columns, so the cost does not grow with
        the program's length)."""
        i = int(np.searchsorted(self.t_s, t_s, side="right"))
        if i <= 0 or i >= self.t_s.size:
            return self.wrench[0 if i <= 0 else -1].copy()
        share = (t_s - self.t_s[i - 1]) / (self.t_s[i] - self.t_s[i - 1])
        return self.wrench[i - 1] + share * (self.wrench[i] - self.wrench[i - 1])

    def grip(self, t_s: float) -> float:
        return float(np.interp(t_s, self.t_s, self.grip_n))


def _raised_cosine(n: int) -> np.ndarray:
    return 0.5 - 0.5 * np.cos(np.linspace(0.0, math.pi, n))


def _slow_noise(rng: np.random.Generator, n: int, corner_samples: float) -> np.ndarray:
    """Smooth zero-mean noise of unit standard deviation, varying over ``corner_samples``."""
    raw = rng.standard_normal(n + int(6 * corner_samples))
    width = max(corner_samples, 1.0)
    taps = np.exp(-0.5 * (np.arange(-3 * width, 3 * width + 1) / width) ** 2)
    smooth = np.convolve(raw, taps / np.sqrt((taps**2).sum()), mode="valid")[:n]
    return smooth


def jig_program(
    experiments: Sequence[Experiment], config: JigConfig, rng: np.random.Generator
) -> LoadProgram:
    """The hand's program for ``experiments`` run one after another (see the module doc)."""
    dt = 1.0 / _PROGRAM_RATE_HZ

    def samples(seconds: float) -> int:
        return max(1, int(round(seconds / dt)))

    pieces: list[np.ndarray] = []
    axis_of: list[np.ndarray] = []
    segments: list[Segment] = []
    before = samples(config.open_s + config.grasp_s + config.settle_s)
    t_cursor = before * dt
    for experiment in experiments:
        column = _AXIS_COLUMN[experiment.axis]
        start = t_cursor
        for pulse in range(experiment.pulses):
            sign = 1.0 if pulse % 2 == 0 else -1.0
            peak = experiment.amplitude_nm * (1.0 - config.amplitude_spread * rng.uniform(0.0, 1.0))
            up = _raised_cosine(samples(rng.uniform(config.ramp_min_s, config.ramp_max_s)))
            hold = np.ones(samples(rng.uniform(config.hold_min_s, config.hold_max_s)))
            down = _raised_cosine(samples(rng.uniform(config.ramp_min_s, config.ramp_max_s)))[::-1]
            rest = np.zeros(samples(rng.uniform(config.rest_min_s, config.rest_max_s)))
            shape = sign * peak * np.concatenate([up, hold, down, rest])
            pieces.append(shape)
            axis_of.append(np.full(shape.size, column))
            t_cursor += shape.size * dt
        segments.append(Segment(experiment.axis, experiment.amplitude_nm, start, t_cursor))
    main = np.concatenate(pieces) if pieces else np.zeros(0)
    columns = np.concatenate(axis_of) if axis_of else np.zeros(0, int)
    n = before + main.size + 1
    wrench = np.zeros((n, 6))
    rows = np.arange(before, before + main.size)
    wrench[rows, columns] = main
    # The hand's imperfection: off-axis torques proportional to the main one, and stray
    # forces, each slowly varying (over about a second).
    corner = _PROGRAM_RATE_HZ * 1.0
    for torque_column in (3, 4, 5):
        off_axis = columns != torque_column
        leak = config.crosstalk * _slow_noise(rng, main.size, corner)
        wrench[rows[off_axis], torque_column] += (np.abs(main) * leak)[off_axis]
    for force_column in (0, 1):
        stray = config.stray_force_n * _slow_noise(rng, main.size, corner)
        wrench[rows, force_column] += stray * np.minimum(
            np.abs(main) / max(np.abs(main).max(), 1e-12), 1.0
        )
    t_s = np.arange(n) * dt
    grip = np.clip((t_s - config.open_s) / max(config.grasp_s, dt), 0.0, 1.0)
    grip = config.grip_force_n * (0.5 - 0.5 * np.cos(math.pi * grip))
    reference = (config.open_s + config.grasp_s, config.open_s + config.grasp_s + config.settle_s)
    return LoadProgram(t_s, wrench, grip, tuple(segments), reference)


def tactile_times(program: LoadProgram, config: JigConfig, rng: np.random.Generator) -> np.ndarray:
    """Capture times of the tactile frames, s: nominal period ``1 / tactile_rate_hz`` with
    independent Gaussian jitter (``tactile_jitter_s``), kept strictly increasing."""
    nominal = np.arange(0.0, program.duration_s, 1.0 / config.tactile_rate_hz)
    jitter = rng.normal(0.0, config.tactile_jitter_s, nominal.size)
    return np.clip(nominal + jitter, 0.0, program.duration_s)


def ft_samples(
    program: LoadProgram, config: JigConfig, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """The force/torque sensor's readings: times (n,) s and wrenches (n, 6) in S (N, N*m),
    the applied wrench plus white noise, at ``ft_rate_hz``."""
    t_s = np.arange(0.0, program.duration_s, 1.0 / config.ft_rate_hz)
    wrench = np.stack([np.interp(t_s, program.t_s, column) for column in program.wrench.T], 1)
    noise = np.array([config.ft_force_noise_n] * 3 + [config.ft_torque_noise_nm] * 3)
    return t_s, wrench + rng.standard_normal(wrench.shape) * noise


class JigGel:
    """The live gel in the jig: ``state(t_s)`` solves the gel model for the grip and the
    live gel's share of the applied wrench at ``t_s``, warm-started from the previous call."""

    def __init__(self, model: GelModel, program: LoadProgram, config: JigConfig) -> None:
        self.model, self.program, self.config = model, program, config
        self._previous: GelState | None = None

    def gel_wrench(self, t_s: float) -> Wrench:
        """The wrench the live gel exerts on the object at ``t_s`` (S; N, N*m)."""
        return Wrench(*(self.config.gel_load_factor * self.program.applied(t_s)))

    def state(self, t_s: float) -> GelState:
        state = self.model.solve(self.program.grip(t_s), self.gel_wrench(t_s), start=self._previous)
        self._previous = state
        return state
