"""Simulated twin of the Robotiq Hand-E (implements ``core.devices.Gripper``).

It behaves as ``drivers.gripper.hande.HandE`` reads the real gripper:

* ``activate()`` does nothing when the gripper is already activated; otherwise it takes
  ``activation_time_s`` on the clock (the twin does not model the fingers' activation
  stroke) and raises DeviceTimeoutError past ``activation_timeout_s``.
* ``move()`` checks and quantises width, speed and force exactly as the real driver (the
  0-255 register counts of ``drivers.gripper.hande_registers``, the same ValueErrors), and
  raises DeviceFaultError (code 0x07) before activation. The fingers then move at the
  commanded speed (no acceleration). An object of width ``object_width_m`` between the
  fingers stops a closing motion there with ``GripperObject.CONTACT_CLOSING``; otherwise the
  fingers stop at the target with ``AT_TARGET``. Widths are reported in whole counts, as the
  real gPO.
* ``inject_fault(code)``: the fingers stop and the status reports the fault. A major fault
  (>= 0x0A) also deactivates the gripper; ``activate()`` resets it, which clears the fault,
  unless it was injected ``sticky`` (then activation fails with DeviceFaultError, as the
  real driver reports a fault that survives the reset). A minor fault (< 0x0A) is cleared
  by the next ``move()``.
* ``set_responding(False)`` makes the gripper silent (wrong baud rate, cut cable): every
  call raises the DeviceTimeoutError the real driver raises after its retries.

Time is the injected clock's (``core.clock``); motion is computed in closed form.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from core.clock import Clock, MonotonicClock
from core.config import Config, check_number, config_dataclass, number
from core.devices import ContextManagedDevice, GripperObject, GripperStatus
from core.errors import DeviceFaultError, DeviceNotConnectedError, DeviceTimeoutError
from drivers.gripper import hande_registers as regs
from drivers.gripper.hande import HandEConfig

_POLL_PERIOD_S = 0.02  # as the real driver polls during activation
_NOT_ACTIVATED_CODE = 0x07


@config_dataclass
class SimGripperSettings(Config):
    """The ``sim:`` section of a gripper YAML.

    ``activation_time_s``: how long activation takes. ``start_width_m``: finger opening at
    start-up (m). ``object_width_m``: width of an object between the fingers (m), or
    ``None`` for none.
    """

    activation_time_s: float = number(0.0, 30.0)
    start_width_m: float = number(0.0, 0.2)
    object_width_m: float | None = number(0.0, 0.2)


@config_dataclass(kw_only=True)
class SimGripperConfig(HandEConfig):
    """A Hand-E YAML with ``backend: sim``: the real driver's keys plus the ``sim:`` section."""

    sim: SimGripperSettings

    def __post_init__(self) -> None:
        super().__post_init__()
        for key in ("start_width_m", "object_width_m"):
            value = getattr(self.sim, key)
            if value is not None and value > self.stroke_m:
                raise ValueError(
                    f"key 'sim.{key}': expected a number in [0, stroke_m={self.stroke_m}], "
                    f"got {value!r}"
                )


@dataclass(frozen=True)
class _Motion:
    """Fingers moving from ``start_m`` at ``t_s`` to ``stop_m`` at ``speed_m_s``; ``result``
    is the object status once stopped."""

    t_s: float
    start_m: float
    stop_m: float
    speed_m_s: float
    result: GripperObject

    def width_at(self, t_s: float) -> float:
        travel = abs(self.stop_m - self.start_m)
        moved = min(travel, self.speed_m_s * max(0.0, t_s - self.t_s))
        return self.start_m + math.copysign(moved, self.stop_m - self.start_m)

    def done_at(self, t_s: float) -> bool:
        return self.speed_m_s * (t_s - self.t_s) >= abs(self.stop_m - self.start_m)


class SimGripper(ContextManagedDevice):
    """The Hand-E twin; see the module docstring. ``clock`` defaults to real time."""

    def __init__(self, config: SimGripperConfig, clock: Clock | None = None) -> None:
        self.config = config
        self.name = config.name
        self._clock = clock if clock is not None else MonotonicClock()
        self._connected = False
        self._responding = True
        self._driver_activated = False  # the real driver's flag, reset by disconnect()
        self._device_activated = False  # the gripper's own gSTA = 3
        self._object_width_m = config.sim.object_width_m
        self._target_m: float | None = None  # the last go-to's width; None: no go-to (gGTO 0)
        self._motion = self._hold(config.sim.start_width_m, GripperObject.AT_TARGET)
        self._fault = 0
        self._sticky = False
        self._force_n = 0.0

    @classmethod
    def from_config(
        cls, config: SimGripperConfig, clock: Clock | None = None, arm: Any = None
    ) -> SimGripper:
        """The twin on ``clock`` (real time when None). ``arm`` is accepted for the same call
        as ``HandE.from_config`` and unused: the twin needs no transport."""
        return cls(config, clock)

    # -- lifecycle ---------------------------------------------------------------------

    def connect(self) -> None:
        """Check that the gripper answers (does not move it)."""
        if self._connected:
            return
        self._connected = True
        try:
            self._check_link("status read")
        except BaseException:
            self.disconnect()
            raise

    def disconnect(self) -> None:
        self._connected = False
        self._driver_activated = False

    @property
    def is_connected(self) -> bool:
        return self._connected

    # -- Gripper -----------------------------------------------------------------------

    def activate(self) -> None:
        """Activate unless already activated; blocks on the clock for ``activation_time_s``."""
        self._check_link("status read")
        if self._device_activated:
            self._driver_activated = True
            return
        if self._sticky and self._fault >= regs.MAJOR_FAULT_MIN:
            raise DeviceFaultError(
                self.name,
                f"activation failed: {regs.fault_message(self._fault)}",
                code=self._fault,
            )
        now = self._clock.now()
        self._fault, self._sticky = 0, False
        self._target_m = None  # the reset cancels any go-to command
        self._motion = self._hold(self._motion.width_at(now), GripperObject.AT_TARGET)
        done_s = now + self.config.sim.activation_time_s
        deadline_s = now + self.config.activation_timeout_s
        while self._clock.now() < done_s:
            if self._clock.now() > deadline_s:
                raise DeviceTimeoutError(
                    self.name,
                    f"activation did not complete within {self.config.activation_timeout_s} s "
                    f"(gSTA={regs.GSTA_ACTIVATING}); check that nothing blocks the fingers",
                )
            self._clock.sleep(_POLL_PERIOD_S)
        self._device_activated = self._driver_activated = True

    def move(self, width_m: float, speed_m_s: float, force_n: float) -> None:
        """Send the fingers toward ``width_m`` (m) at ``speed_m_s`` (m/s, 0.020-0.150) with
        ``force_n`` (N, 20-185), quantised to register counts as the real gripper does."""
        cfg = self.config
        position = regs.position_count(width_m, cfg.open_count, cfg.closed_count, cfg.stroke_m)
        speed_count = regs.speed_count(speed_m_s)
        force_count = regs.force_count(force_n)
        if not self._driver_activated:
            raise DeviceFaultError(
                self.name, "not activated: call activate() before move()", code=_NOT_ACTIVATED_CODE
            )
        self._check_link("command write")
        if not self._device_activated:
            return  # the gripper ignores go-to commands until it is re-activated
        self._fault = 0  # only a minor fault can be present here: the new action clears it
        low, high = regs.SPEED_RANGE_M_S
        self._target_m = self._width_of(position)
        low_n, high_n = regs.FORCE_RANGE_N
        self._force_n = low_n + force_count / 0xFF * (high_n - low_n)
        self._start_motion(self._target_m, low + speed_count / 0xFF * (high - low))

    def read_status(self) -> GripperStatus:
        """One status reading; faults are reported in it, not raised."""
        self._check_link("status read")
        now = self._clock.now()
        motion = self._motion
        if self._target_m is None:
            obj = GripperObject.AT_TARGET  # no go-to in progress: the real driver's reading
        else:
            obj = motion.result if motion.done_at(now) else GripperObject.MOVING
        return GripperStatus(
            t_s=now,
            activated=self._device_activated,
            moving=obj is GripperObject.MOVING,
            object=obj,
            width_m=self._width_of(self._count_of(motion.width_at(now))),
            fault_code=self._fault,
            fault_message=regs.fault_message(self._fault),
        )

    # -- simulation hooks --------------------------------------------------------------

    @property
    def commanded_force_n(self) -> float:
        """The grip force of the last accepted ``move()``, N, as its register count
        quantises it (0 before any); what a scene presses a held object with."""
        return self._force_n

    def set_object_width(self, width_m: float | None) -> None:
        """Put an object of ``width_m`` (m) between the fingers, or remove it (``None``); a
        motion under way is re-planned from the current opening."""
        if width_m is not None:
            check_number("object_width_m", width_m, 0.0, self.config.stroke_m)
        self._object_width_m = width_m
        if self._target_m is not None:
            self._start_motion(self._target_m, self._motion.speed_m_s)

    def inject_fault(self, code: int, sticky: bool = False) -> None:
        """Report gripper fault ``code`` (gFLT, 1-15) and stop; see the module docstring."""
        if isinstance(code, bool) or not isinstance(code, int) or not 1 <= code <= 0x0F:
            raise ValueError(f"code: expected a gFLT fault code in [1, 15], got {code!r}")
        now = self._clock.now()
        width = self._motion.width_at(now)
        self._motion = self._hold(width, GripperObject.AT_TARGET)
        self._fault, self._sticky = code, sticky
        if code >= regs.MAJOR_FAULT_MIN:
            self._device_activated = False
            self._target_m = None

    def set_responding(self, responding: bool) -> None:
        """Make the gripper answer (True) or stay silent (False)."""
        self._responding = responding

    # -- internals ---------------------------------------------------------------------

    def _check_link(self, what: str) -> None:
        if not self._connected:
            raise DeviceNotConnectedError(self.name, f"{what}: not connected; call connect()")
        if not self._responding:
            cfg = self.config
            raise DeviceTimeoutError(
                self.name,
                f"{what}: no valid answer after {1 + cfg.retries} attempt(s) of "
                f"{cfg.timeout_s} s. Check the baud rate and slave id (Hand-E default: 115200 "
                "baud 8N1, slave id 9), the RS-485 wiring and the gripper's 24 V supply",
            )

    def _start_motion(self, target_m: float, speed_m_s: float) -> None:
        now = self._clock.now()
        width = self._motion.width_at(now)
        stop, result = target_m, GripperObject.AT_TARGET
        obj = self._object_width_m
        if obj is not None and stop < obj <= width:
            stop, result = obj, GripperObject.CONTACT_CLOSING
        self._motion = _Motion(now, width, stop, speed_m_s, result)

    def _hold(self, width_m: float, result: GripperObject) -> _Motion:
        return _Motion(self._clock.now(), width_m, width_m, 1.0, result)

    def _count_of(self, width_m: float) -> int:
        cfg = self.config
        return regs.position_count(width_m, cfg.open_count, cfg.closed_count, cfg.stroke_m)

    def _width_of(self, count: int) -> float:
        cfg = self.config
        return regs.width_from_count(count, cfg.open_count, cfg.closed_count, cfg.stroke_m)
