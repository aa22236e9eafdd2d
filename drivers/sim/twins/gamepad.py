"""Simulated twin of the SDL gamepad (implements ``core.devices.Gamepad``): scripted input.

A script is a timeline of ``PadEvent``s. Each event, at ``t_s`` seconds after ``play()``
on the injected clock (``core.clock``), sets some actions (by the action names of
the ``GamepadConfig`` mapping: axis values in [-1, 1] after the dead zone, buttons pressed
or not) and may unplug (``attached=False``) or plug in (``attached=True``) the pad.
``play()`` starts from neutral input (axes 0, buttons released); actions an event does not
name keep their values.

``read()`` behaves as ``drivers.gamepad.pad.PygameGamepad.read``: while the pad is
unplugged it returns ``connected=False`` with every axis 0.0 and every button released,
without raising; when the pad comes back, the scripted values show again. ``connect()``
raises DeviceNotConnectedError when no pad is attached, ``read()`` before ``connect()``
too. ``is_connected`` is True between ``connect()`` and ``disconnect()``, even while the pad
is unplugged.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType

from core.clock import Clock, MonotonicClock
from core.config import Config, config_dataclass
from core.devices import ContextManagedDevice, GamepadState
from core.errors import DeviceNotConnectedError
from drivers.gamepad.mapping import GamepadConfig


@config_dataclass
class SimGamepadSettings(Config):
    """The ``sim:`` section of a gamepad YAML. ``attached``: whether a pad is plugged in at
    start-up."""

    attached: bool


@config_dataclass(kw_only=True)
class SimGamepadConfig(GamepadConfig):
    """A gamepad YAML with ``backend: sim``: the real mapping plus the ``sim:`` section."""

    sim: SimGamepadSettings


@dataclass(frozen=True)
class PadEvent:
    """At ``t_s`` (s after ``play()``): set these axis and button actions, and plug the pad
    in (``attached=True``) or out (``False``) unless ``attached`` is None."""

    t_s: float
    axes: Mapping[str, float] = field(default_factory=dict)
    buttons: Mapping[str, bool] = field(default_factory=dict)
    attached: bool | None = None

    def __post_init__(self) -> None:
        if not math.isfinite(self.t_s) or self.t_s < 0:
            raise ValueError(f"t_s: expected a finite time >= 0, got {self.t_s!r}")
        for action, value in self.axes.items():
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise ValueError(f"axes.{action}: expected a number in [-1, 1], got {value!r}")
            if not -1.0 <= value <= 1.0:
                raise ValueError(f"axes.{action}: expected a number in [-1, 1], got {value!r}")
        for action, pressed in self.buttons.items():
            if not isinstance(pressed, bool):
                raise ValueError(f"buttons.{action}: expected true or false, got {pressed!r}")
        object.__setattr__(self, "axes", MappingProxyType(dict(self.axes)))
        object.__setattr__(self, "buttons", MappingProxyType(dict(self.buttons)))


class SimGamepad(ContextManagedDevice):
    """The gamepad twin; see the module docstring. ``clock`` defaults to real time."""

    def __init__(self, config: SimGamepadConfig, clock: Clock | None = None) -> None:
        self.config = config
        self.name = config.name
        self._clock = clock if clock is not None else MonotonicClock()
        self._open = False
        self._attached = config.sim.attached
        self._axes = {action: 0.0 for action in config.axes}
        self._buttons = {action: False for action in config.buttons}
        self._script: tuple[PadEvent, ...] = ()
        self._start_s = 0.0
        self._next = 0  # index of the first event not yet applied

    @classmethod
    def from_config(cls, config: SimGamepadConfig, clock: Clock | None = None) -> SimGamepad:
        """The twin on ``clock`` (real time when None)."""
        return cls(config, clock)

    def play(self, events: Sequence[PadEvent]) -> None:
        """Start the script now, from neutral input; events must be in time order and name
        only actions of the mapping."""
        times = [event.t_s for event in events]
        if times != sorted(times):
            raise ValueError(f"events: expected times in increasing order, got {times}")
        for event in events:
            for kind, known, names in (
                ("axis", self.config.axes, event.axes),
                ("button", self.config.buttons, event.buttons),
            ):
                unknown = sorted(set(names) - set(known))
                if unknown:
                    raise ValueError(
                        f"event at {event.t_s} s: unknown {kind} action '{unknown[0]}'; "
                        f"the mapping has: {', '.join(known)}"
                    )
        self._script = tuple(events)
        self._start_s = self._clock.now()
        self._next = 0
        self._axes = {action: 0.0 for action in self.config.axes}
        self._buttons = {action: False for action in self.config.buttons}

    # -- lifecycle ---------------------------------------------------------------------

    @property
    def is_connected(self) -> bool:
        """True between ``connect()`` and ``disconnect()``, even while the pad is unplugged."""
        return self._open

    def connect(self) -> None:
        """Open the pad; raises DeviceNotConnectedError if none is attached."""
        if self._open:
            return
        self._apply_due_events()
        if not self._attached:
            raise DeviceNotConnectedError(
                self.name,
                "no game controller attached (the simulated pad is unplugged); check the USB "
                "cable or the Bluetooth pairing",
            )
        self._open = True

    def disconnect(self) -> None:
        self._open = False

    def read(self) -> GamepadState:
        """The scripted state now (``t_s`` on the clock); safe neutral values while unplugged."""
        if not self._open:
            raise DeviceNotConnectedError(self.name, "read() called before connect()")
        self._apply_due_events()
        t_s = self._clock.now()
        if not self._attached:
            return GamepadState.unplugged(t_s, self._axes, self._buttons)
        return GamepadState(
            t_s=t_s, connected=True, axes=dict(self._axes), buttons=dict(self._buttons)
        )

    def _apply_due_events(self) -> None:
        elapsed_s = self._clock.now() - self._start_s
        while self._next < len(self._script) and self._script[self._next].t_s <= elapsed_s:
            event = self._script[self._next]
            self._axes.update({action: float(value) for action, value in event.axes.items()})
            self._buttons.update(event.buttons)
            if event.attached is not None:
                self._attached = event.attached
            self._next += 1
