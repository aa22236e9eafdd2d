"""Simulated six-axis force/torque sensor (implements ``core.devices.ForceTorqueSensor``).

The calibration jig's ground truth. No real force/torque driver exists yet, so this twin is
the only backend of its registry type. Each ``read()`` returns the wrench that the **wrench
source** gives for the clock's ``now()`` (``core.clock``), plus independent Gaussian
noise per component (``force_noise_n``, ``torque_noise_nm``) drawn from the injected ``rng``
in call order, in the configured ``frame``.

A wrench source is any callable ``source(t_s) -> (force_n, torque_nm)``, each three numbers
(N, N*m); ``scripted_wrench`` makes a piecewise-constant one from a timeline. The default is
the zero wrench.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from core.clock import Clock, MonotonicClock
from core.config import Config, config_dataclass, number
from core.devices import ContextManagedDevice, Vector3, WrenchSample
from core.errors import DeviceNotConnectedError

WrenchSource = Callable[[float], tuple[Sequence[float], Sequence[float]]]
"""Gives (force in N, torque in N*m), three components each, at a time in s."""


@config_dataclass
class SimForceTorqueSettings(Config):
    """The ``sim:`` section: noise standard deviations per component (N, N*m) and the seed
    of the twin's randomness when the registry builds it."""

    force_noise_n: float = number(0.0, 100.0)
    torque_noise_nm: float = number(0.0, 10.0)
    seed: int = number(0, 2**32 - 1)


@config_dataclass
class SimForceTorqueConfig(Config):
    """A force/torque sensor YAML (``backend: sim``). ``frame``: name of the frame the
    wrench is expressed in (e.g. ``"S"``, the tactile sensor's)."""

    name: str
    frame: str
    sim: SimForceTorqueSettings


def scripted_wrench(steps: Sequence[tuple[float, Vector3, Vector3]]) -> WrenchSource:
    """A piecewise-constant source: ``(t_s, force_n, torque_nm)`` steps in time order, each
    holding from its ``t_s`` (clock time) until the next; zero before the first."""
    times = [float(t) for t, _, _ in steps]
    if times != sorted(times) or not all(math.isfinite(t) for t in times):
        raise ValueError(f"steps: expected finite times in increasing order, got {times}")
    values = [(tuple(force), tuple(torque)) for _, force, torque in steps]

    def source(t_s: float) -> tuple[Sequence[float], Sequence[float]]:
        index = int(np.searchsorted(times, t_s, side="right")) - 1
        return values[index] if index >= 0 else ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0))

    return source


def _zero_wrench(t_s: float) -> tuple[Sequence[float], Sequence[float]]:
    return (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)


class SimForceTorque(ContextManagedDevice):
    """The force/torque twin; see the module docstring. ``clock`` defaults to real time,
    ``rng`` to ``numpy.random.default_rng(config.sim.seed)``."""

    def __init__(
        self,
        config: SimForceTorqueConfig,
        clock: Clock | None = None,
        rng: np.random.Generator | None = None,
        source: WrenchSource | None = None,
    ) -> None:
        self.config = config
        self.name = config.name
        self._clock = clock if clock is not None else MonotonicClock()
        self._rng = rng if rng is not None else np.random.default_rng(config.sim.seed)
        self._source = source if source is not None else _zero_wrench
        self._connected = False

    @classmethod
    def from_config(
        cls, config: SimForceTorqueConfig, clock: Clock | None = None
    ) -> SimForceTorque:
        """The twin on ``clock`` (real time when None), seeded by ``config.sim.seed``."""
        return cls(config, clock)

    def set_source(self, source: WrenchSource | None) -> None:
        """Read the wrench from ``source`` from now on (None: the zero wrench)."""
        self._source = source if source is not None else _zero_wrench

    @property
    def is_connected(self) -> bool:
        return self._connected

    def connect(self) -> None:
        self._connected = True

    def disconnect(self) -> None:
        self._connected = False

    def read(self) -> WrenchSample:
        """The source's wrench now, plus noise."""
        if not self._connected:
            raise DeviceNotConnectedError(self.name, "not connected; call connect() first")
        t_s = self._clock.now()
        force, torque = self._source(t_s)
        wrench = np.array([*force, *torque], dtype=float)
        if wrench.shape != (6,) or not np.all(np.isfinite(wrench)):
            raise ValueError(
                f"wrench source: expected three finite force and three torque components, "
                f"got {force!r}, {torque!r}"
            )
        sim = self.config.sim
        sigma = np.repeat([sim.force_noise_n, sim.torque_noise_nm], 3)
        wrench += self._rng.normal(0.0, 1.0, 6) * sigma
        fx, fy, fz, tx, ty, tz = (float(v) for v in wrench)
        return WrenchSample(
            t_s=t_s, force_n=(fx, fy, fz), torque_nm=(tx, ty, tz), frame=self.config.frame
        )
