"""Gamepad arbitration: ``GamepadState`` (named actions) -> ``TeleopInput`` for one tick.

The pad's mapping (``drivers.gamepad.mapping.GamepadConfig``, e.g. configs/gamepad/xbox.yaml)
names the actions; this module reads them by name and needs nothing else of the pad:

* axes ``vx``, ``vy``, ``vz`` (TCP linear velocity along x, y, z of the base frame B) and
  ``wx``, ``wy``, ``wz`` (angular velocity about them), each in [-1, 1] after the pad's dead
  zone; an action the mapping does not bind reads 0;
* buttons ``hand_back``, ``estop``, ``estop_ack``, ``gripper_open``, ``gripper_close`` and
  ``deadman``; an unbound one reads released.

Rules (``TeleopArbiter.update``, once per control tick):

* **Takeover**: any axis past ``takeover_threshold`` (0: any value the pad's dead zone lets
  through) while the ``deadman`` button is held gives the operator control at once
  (``in_control``). The twist is zero while the deadman is released. The deadman is a safety
  rule, not a setting: no file or override can switch it off (``TeleopConfig.safety_rules``).
* **Twist**: linear actions times ``stick_speed_m_s``, angular ones times
  ``stick_angular_speed_rad_s``; each vector's norm is then capped at that speed, so a diagonal
  is no faster than an axis. Zero unless in control.
* **Hand-back** (rising edge of ``hand_back``): releases control. Axes still deflected at
  that moment do not take over again until every axis has come back to neutral, so holding a
  stick through the press does not snatch control straight back.
* **E-stop**: ``estop`` is reported while held (the machine latches it); ``estop_ack``,
  ``gripper_open`` and ``gripper_close`` are rising edges (one press, one event).
* **Lost pad**: while the pad is unplugged (``connected`` False) its input is neutral; if the
  operator was in control, ``in_control`` stays True with a zero twist, which the watchdog
  (``controller.safety.Watchdog``) trips on: ``lost_in_control(teleop_input)``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import ClassVar

import numpy as np

from controller.insertion.interface import TeleopInput
from core.config import Config, config_dataclass, number
from core.devices import GamepadState, Twist
from core.envelope import MAX_ANGULAR_SPEED_RAD_S, MAX_LINEAR_SPEED_M_S

LINEAR_ACTIONS = ("vx", "vy", "vz")
ANGULAR_ACTIONS = ("wx", "wy", "wz")
EDGE_BUTTONS = ("hand_back", "estop_ack", "gripper_open", "gripper_close")


@config_dataclass
class TeleopConfig(Config):
    """The task YAML's ``teleop:`` section.

    ``stick_speed_m_s``: TCP speed at full stick deflection (m/s, in B), the operator's
    top speed (at most ``limits.max_linear_speed_m_s``: controller/limit_checks.py).
    ``stick_angular_speed_rad_s``: TCP angular speed at full deflection (rad/s, in B), at
    most ``limits.max_angular_speed_rad_s``.
    ``takeover_threshold``: action magnitude (after the pad's dead zone, 0..1) above which an
    axis takes over; 0 means any input the dead zone lets through.
    Takeover and motion always need the ``deadman`` button held (module doc).
    """

    safety_rules: ClassVar[Mapping[str, str]] = {
        "require_deadman": "takeover and motion always need the deadman held",
    }

    stick_speed_m_s: float = number(0.0, MAX_LINEAR_SPEED_M_S, default=0.02)
    stick_angular_speed_rad_s: float = number(0.0, MAX_ANGULAR_SPEED_RAD_S, default=0.2)
    takeover_threshold: float = number(0.0, 0.9, default=0.0)


def lost_in_control(teleop: TeleopInput) -> bool:
    """The operator holds control but the pad is gone: the watchdog trips on this."""
    return teleop.in_control and not teleop.connected


class TeleopArbiter:
    """Turns one ``GamepadState`` per tick into a ``TeleopInput`` (see the module doc)."""

    def __init__(self, config: TeleopConfig) -> None:
        self.config = config
        self._in_control = False
        self._rearmed = True  # sticks returned to neutral since the last hand-back
        self._pressed: dict[str, bool] = dict.fromkeys(EDGE_BUTTONS, False)

    @property
    def in_control(self) -> bool:
        return self._in_control

    def update(self, state: GamepadState | None) -> TeleopInput:
        """This tick's arbitration from the pad's state (None: no pad configured)."""
        if state is None:
            return TeleopInput(in_control=self._in_control)
        buttons = state.buttons if state.connected else {}
        axes = state.axes if state.connected else {}
        edges = {name: bool(buttons.get(name, False)) and not self._pressed[name]
                 for name in EDGE_BUTTONS}  # fmt: skip
        self._pressed = {name: bool(buttons.get(name, False)) for name in EDGE_BUTTONS}
        deadman = bool(buttons.get("deadman", False))

        linear = np.array([float(axes.get(a, 0.0)) for a in LINEAR_ACTIONS])
        angular = np.array([float(axes.get(a, 0.0)) for a in ANGULAR_ACTIONS])
        deflected = bool(
            np.any(np.abs(np.concatenate([linear, angular])) > self.config.takeover_threshold)
        )
        if edges["hand_back"] and self._in_control:
            self._in_control = False
            self._rearmed = False
        elif not deflected:
            self._rearmed = True
        elif self._rearmed and deadman:
            self._in_control = True

        twist = Twist()
        if self._in_control and deadman and state.connected:
            twist = Twist(
                _capped(linear * self.config.stick_speed_m_s,
                        self.config.stick_speed_m_s),
                _capped(angular * self.config.stick_angular_speed_rad_s,
                        self.config.stick_angular_speed_rad_s),
            )  # fmt: skip
        return TeleopInput(
            connected=state.connected,
            in_control=self._in_control,
            twist=twist,
            gripper_open=edges["gripper_open"],
            gripper_close=edges["gripper_close"],
            hand_back=edges["hand_back"],
            estop=bool(buttons.get("estop", False)),
            estop_ack=edges["estop_ack"],
            deadman=deadman,
        )


def _capped(vector: np.ndarray, limit: float) -> tuple[float, float, float]:
    """``vector`` scaled down to norm ``limit`` if longer (direction kept)."""
    norm = float(np.linalg.norm(vector))
    if norm > limit:
        vector = vector * (limit / norm)
    x, y, z = (float(v) for v in vector)
    return (x, y, z)
