"""The arm driver: UFACTORY xArm6 over xarm-python-sdk, behind a pure safety envelope."""

from drivers.arm.arm_envelope import SafetyEnvelope
from drivers.arm.xarm6 import TcpConfig, XArm6, XArm6Config

__all__ = ["SafetyEnvelope", "TcpConfig", "XArm6", "XArm6Config"]
