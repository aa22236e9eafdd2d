"""The press-spiral machine (``SpiralMachine``): a force-threshold spiral with yaw steps, on
the tactile axial force (the product, ``dipole``, and its variants) or on the arm's F/T
sensor (the ``blind`` baseline). One module per phase; the table and sub-stages in
``spiral_machine.SPIRAL``."""

from controller.insertion.spiral.spiral_config import AxialWeights, SpiralConfig, TouchSpiralConfig
from controller.insertion.spiral.spiral_machine import NO_FORCE, SPIRAL, SpiralMachine

__all__ = [
    "NO_FORCE", "SPIRAL", "AxialWeights", "SpiralConfig", "SpiralMachine", "TouchSpiralConfig",
]  # fmt: skip
