"""Gamepad driver (SDL game-controller API through pygame): Xbox, PS4 and PS5 pads by name.

The mapping (``GamepadConfig``) needs no SDL; the driver itself is ``drivers.gamepad.pad``
(``PygameGamepad``), which imports pygame and is imported only when a real pad is built.
"""

from drivers.gamepad.mapping import AxisBinding, GamepadConfig, axis_value

__all__ = ["AxisBinding", "GamepadConfig", "axis_value"]
