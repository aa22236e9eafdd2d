"""Gamepad driver (SDL game-controller API through pygame): Xbox, PS4 and PS5 pads by name."""

from drivers.gamepad.mapping import AxisBinding, GamepadConfig, axis_value
from drivers.gamepad.pad import PygameGamepad

__all__ = ["AxisBinding", "GamepadConfig", "PygameGamepad", "axis_value"]
