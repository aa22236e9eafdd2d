"""Typed errors raised by every device driver, real or simulated.

The tree is ``DeviceError`` > ``DeviceNotConnectedError``, ``DeviceTimeoutError``,
``DeviceFaultError``, ``DevicesNotReady`` (a run's devices that could not all be
connected, each named). Each error names the device and carries the device's own error
code and message when it has one, so a user can look the code up in the vendor manual.
"""

from __future__ import annotations


class DeviceError(Exception):
    """A device failed. ``device`` names it (e.g. ``"xarm6"``), ``code`` is the device's own
    error code if it reported one, ``message`` says what happened and what to check."""

    def __init__(self, device: str, message: str, code: int | None = None) -> None:
        self.device = device
        self.message = message
        self.code = code
        suffix = f" (device code {code})" if code is not None else ""
        super().__init__(f"{device}: {message}{suffix}")


class DeviceNotConnectedError(DeviceError):
    """The device is absent, unplugged, or was used before ``connect()``."""


class DeviceTimeoutError(DeviceError):
    """The device did not answer in time, or its newest sample is older than allowed."""


class DeviceFaultError(DeviceError):
    """The device reports a fault (an error code, a protective stop, a gripper fault)."""


class DevicesNotReady(DeviceError):
    """Some of a run's devices could not be connected; ``failures`` maps each one's role
    (arm, gripper, tactile, gamepad) to its error, and the message names them all."""

    def __init__(self, failures: dict[str, DeviceError]) -> None:
        self.failures = failures
        roles = ", ".join(failures)
        details = "; ".join(f"{role}: {error}" for role, error in failures.items())
        super().__init__(roles, f"not ready: {details}")
