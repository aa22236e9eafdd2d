"""Gamepad mapping: named actions -> SDL game-controller axes and buttons, and axis shaping.

This module needs no SDL: it holds the configuration (``GamepadConfig``, loaded from YAML
like every device config: ``drivers.registry`` and ``core.config.build``), and the
pure function that turns a raw controller axis into an action value.

Names are SDL's game-controller names (``SDL_GameControllerGetStringForAxis/Button``), the
same for Xbox, PS4 (DualShock 4) and PS5 (DualSense) pads: ``a`` is the bottom face button
(Cross on PlayStation), ``b`` the right one (Circle), ``x`` the left one (Square), ``y`` the
top one (Triangle); ``leftshoulder`` is LB / L1, ``lefttrigger`` LT / L2, ``back`` View /
Share / Create, ``start`` Menu / Options.

Raw ranges (SDL_GameControllerGetAxis): sticks -32768..32767 with x positive to the right and
**y positive down**; triggers 0 (released)..32767 (pressed).

Dead zone: **per axis** (axial), applied to each bound axis on its own. An action value is 0
while ``|u| <= dead_zone`` (``u`` the raw value divided by 32767, clipped to [-1, 1]) and
``sign(u) * (|u| - dead_zone) / (1 - dead_zone)`` beyond, so it rises continuously from 0 at
the dead-zone edge to +-1 at full deflection; then ``invert`` flips the sign and ``scale``
(0 < scale <= 1) multiplies it. An axial zone was chosen over a radial one because each action
commands one robot axis: thumb wobble across the pushed direction stays filtered out (no drift
of ``vy`` while pushing ``vx``), and the same rule serves triggers, which have no partner axis.
Action values are dimensionless in [-1, 1]; the teleoperation layer turns them into m/s, rad/s.
"""

from __future__ import annotations

import typing
from collections.abc import Mapping
from typing import Literal

from core.config import Config, config_dataclass, number

AxisName = Literal["leftx", "lefty", "rightx", "righty", "lefttrigger", "righttrigger"]
ButtonName = Literal[
    "a", "b", "x", "y", "back", "guide", "start", "leftstick", "rightstick",
    "leftshoulder", "rightshoulder", "dpup", "dpdown", "dpleft", "dpright",
]  # fmt: skip
AXIS_NAMES: tuple[str, ...] = typing.get_args(AxisName)
BUTTON_NAMES: tuple[str, ...] = typing.get_args(ButtonName)
SAFETY_BUTTONS = ("deadman", "estop", "hand_back")
"""Button actions every mapping must bind: ``deadman`` (motion commands count only while it
is held), ``estop`` (request a stop; a software request, not a safety-rated e-stop) and
``hand_back`` (hand control back to autonomy)."""

AXIS_FULL_SCALE = 32767
MAX_DEAD_ZONE = 0.5


@config_dataclass
class AxisBinding(Config):
    """One analog action: the SDL axis it reads, whether its sign is flipped, and its gain.

    ``scale`` multiplies the shaped value, 0 < scale <= 1, so actions stay in [-1, 1].
    """

    axis: AxisName
    invert: bool = False
    scale: float = number(0.0, 1.0, default=1.0)

    def __post_init__(self) -> None:
        if self.scale == 0:
            raise ValueError("key 'scale': expected a number in (0, 1], got 0")


@config_dataclass
class GamepadConfig(Config):
    """The pad's mapping.

    ``axes``: action name -> ``AxisBinding`` (e.g. ``vx``, ``vy``, ``vz``, ``wz``).
    ``buttons``: action name -> SDL button name; must bind ``deadman``, ``estop`` and
    ``hand_back`` (``SAFETY_BUTTONS``), on distinct buttons.
    ``dead_zone``: per-axis dead zone as a fraction of full deflection, in [0, 0.5].
    ``name``: device name used in errors and logs.
    """

    axes: Mapping[str, AxisBinding]
    buttons: Mapping[str, ButtonName]
    dead_zone: float = number(0.0, MAX_DEAD_ZONE, default=0.15)
    name: str = "gamepad"

    def __post_init__(self) -> None:
        for action in self.axes:
            _check_action_name(f"axes.{action}", action)
        _check_distinct("axes", {action: b.axis for action, b in self.axes.items()})
        for action in self.buttons:
            _check_action_name(f"buttons.{action}", action)
        missing = [action for action in SAFETY_BUTTONS if action not in self.buttons]
        if missing:
            raise ValueError(f"key 'buttons': missing required action(s) {', '.join(missing)}")
        _check_distinct("buttons", dict(self.buttons))


def axis_value(raw: int, binding: AxisBinding, dead_zone: float) -> float:
    """Action value in [-1, 1] from a raw SDL controller axis reading (see the module doc)."""
    unit = min(1.0, max(-1.0, raw / AXIS_FULL_SCALE))
    magnitude = abs(unit)
    if magnitude <= dead_zone:
        return 0.0
    shaped = (magnitude - dead_zone) / (1.0 - dead_zone)
    sign = -1.0 if (unit < 0) != binding.invert else 1.0
    return sign * shaped * binding.scale


def _check_action_name(key: str, action: object) -> None:
    if not isinstance(action, str) or not action.isidentifier():
        raise ValueError(f"key '{key}': expected an action name (identifier), got {action!r}")


def _check_distinct(key: str, bound: dict[str, str]) -> None:
    seen: dict[str, str] = {}
    for action, control in bound.items():
        if control in seen:
            raise ValueError(
                f"key '{key}': actions '{seen[control]}' and '{action}' both use '{control}'"
            )
        seen[control] = action
