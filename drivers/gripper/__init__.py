"""Gripper drivers: the Robotiq Hand-E over Modbus RTU."""

from drivers.gripper.hande import HandE, HandEConfig

__all__ = ["HandE", "HandEConfig"]
