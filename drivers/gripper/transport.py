"""How the Hand-E driver reaches its Modbus registers: the ``RegisterTransport`` interface and
the xArm tool port transport (the USB-RS485 one, over pymodbus, is ``modbus_rtu``, imported
only when a serial Hand-E is built).

Each transport implements ``RegisterTransport``: one attempt per call (the driver owns
retries and pacing), each attempt bounded in time, registers as 16-bit integers, failures
as typed ``DeviceError``s:

- ``DeviceTimeoutError``: no valid reply in time (silence, or a reply that failed its CRC or
  length check); the driver retries these.
- ``DeviceFaultError``: the gripper answered with a Modbus exception (``code`` = exception code).
- ``DeviceNotConnectedError``: the port or the arm is not there.
"""

from __future__ import annotations

import struct
from collections.abc import Sequence
from typing import Any, Protocol

from core.errors import (
    DeviceError,
    DeviceFaultError,
    DeviceNotConnectedError,
    DeviceTimeoutError,
)

# Modbus application protocol v1.1b3, section 7: exception codes.
MODBUS_EXCEPTIONS = {
    1: "illegal function",
    2: "illegal data address",
    3: "illegal data value",
    4: "server device failure",
    5: "acknowledge",
    6: "server device busy",
    8: "memory parity error",
    10: "gateway path unavailable",
    11: "gateway target device failed to respond",
}

READ_HOLDING_REGISTERS = 0x03  # the manual's examples read the status with FC03
WRITE_MULTIPLE_REGISTERS = 0x10


class RegisterTransport(Protocol):
    """Reads and writes 16-bit registers of one Modbus slave; one attempt per call."""

    description: str  # where the gripper is, for error messages (port, baud, slave id)

    def open(self) -> None: ...

    def close(self) -> None:
        """Release the link; idempotent and never raises."""
        ...

    def read_registers(self, address: int, count: int) -> list[int]: ...

    def write_registers(self, address: int, values: Sequence[int]) -> None: ...


def exception_text(code: int) -> str:
    return f"Modbus exception {code} ({MODBUS_EXCEPTIONS.get(code, 'unknown')})"


# xArm SDK API codes (xarm/x3/code.py, APIState) that this transport tells apart.
XARM_NOT_CONNECTED = -1
XARM_HAS_ERROR = 1  # the controller reports an error; for the tool port: C19 / C28
XARM_RES_TIMEOUT = 3
XARM_HOST_ID_ERR = 20
XARM_MODBUS_BAUD_NOT_CORRECT = 22
XARM_MODBUS_ERR_LENG = 23
XARM_END_EFFECTOR_COMM_ERRORS = {
    19: "C19 end effector communication error",
    28: "C28 end module communication error",
}


class XArmToolTransport:
    """Modbus RTU through the xArm's tool RS-485 port, via ``XArmAPI``.

    ``arm.getset_tgpio_modbus_data(datas)`` sends ``[slave id, function code, data...]``;
    the controller adds the CRC and returns ``(code, response)``, ``response`` being the
    reply from its slave id on, without CRC, and ``code`` an xArm API code (0 = success).
    """

    def __init__(
        self,
        arm: Any,
        *,
        slave_id: int,
        baudrate: int,
        timeout_s: float,
        device: str = "hande",
    ) -> None:
        self._arm = arm
        self._slave_id = slave_id
        self._baudrate = baudrate
        self._timeout_s = timeout_s
        self._device = device
        self.description = f"xArm tool RS-485 port at {baudrate} baud, slave id {slave_id}"

    def open(self) -> None:
        if not getattr(self._arm, "connected", False):
            raise DeviceNotConnectedError(
                self._device, "the xArm is not connected; connect the arm before the gripper"
            )
        code = self._arm.set_tgpio_modbus_baudrate(self._baudrate)
        if code != 0:
            raise DeviceNotConnectedError(
                self._device,
                f"the xArm refused tool RS-485 baud rate {self._baudrate} (API code {code})",
                code=code,
            )
        code = self._arm.set_tgpio_modbus_timeout(round(self._timeout_s * 1000))
        if code != 0:
            raise DeviceNotConnectedError(
                self._device,
                f"the xArm refused tool RS-485 timeout {self._timeout_s} s (API code {code})",
                code=code,
            )

    def close(self) -> None:
        """Nothing to release: the arm driver owns the connection to the controller."""

    def read_registers(self, address: int, count: int) -> list[int]:
        what = f"read of {count} registers at 0x{address:04X}"
        reply = self._exchange(
            what, struct.pack(">BBHH", self._slave_id, READ_HOLDING_REGISTERS, address, count)
        )
        if len(reply) < 3 or reply[2] != 2 * count or len(reply) < 3 + 2 * count:
            raise DeviceTimeoutError(
                self._device,
                f"{what}: malformed reply {bytes(reply).hex(' ')} on {self.description}",
            )
        return list(struct.unpack(f">{count}H", bytes(reply[3 : 3 + 2 * count])))

    def write_registers(self, address: int, values: Sequence[int]) -> None:
        count = len(values)
        what = f"write of {count} registers at 0x{address:04X}"
        request = struct.pack(
            f">BBHHB{count}H",
            self._slave_id,
            WRITE_MULTIPLE_REGISTERS,
            address,
            count,
            2 * count,
            *values,
        )
        reply = self._exchange(what, request)
        if bytes(reply[2:6]) != struct.pack(">HH", address, count):
            raise DeviceTimeoutError(
                self._device,
                f"{what}: malformed reply {bytes(reply).hex(' ')} on {self.description}",
            )

    def _exchange(self, what: str, request: bytes) -> list[int]:
        code, reply = self._arm.getset_tgpio_modbus_data(list(request))
        if code != 0:
            raise self._api_error(what, code)
        reply = list(reply)
        function = request[1]
        if len(reply) >= 3 and reply[0] == self._slave_id and reply[1] == function | 0x80:
            raise DeviceFaultError(
                self._device,
                f"{what}: gripper answered {exception_text(reply[2])}",
                code=reply[2],
            )
        if len(reply) < 2 or reply[0] != self._slave_id or reply[1] != function:
            raise DeviceTimeoutError(
                self._device,
                f"{what}: unexpected reply {bytes(reply).hex(' ')} on {self.description}",
            )
        return reply

    def _api_error(self, what: str, code: int) -> DeviceError:
        where = self.description
        if code == XARM_NOT_CONNECTED:
            return DeviceNotConnectedError(
                self._device, f"{what}: the xArm is not connected", code=code
            )
        if code == XARM_HAS_ERROR:
            arm_error = getattr(self._arm, "error_code", 0)
            meaning = XARM_END_EFFECTOR_COMM_ERRORS.get(arm_error, f"controller error {arm_error}")
            return DeviceTimeoutError(
                self._device,
                f"{what}: no answer on {where}: xArm reports {meaning}; check the gripper's "
                "baud rate, slave id and cable, then clear the arm error (clean_error)",
                code=code,
            )
        if code in (XARM_RES_TIMEOUT, XARM_HOST_ID_ERR, XARM_MODBUS_ERR_LENG):
            return DeviceTimeoutError(
                self._device,
                f"{what}: no valid reply on {where} (xArm API code {code})",
                code=code,
            )
        if code == XARM_MODBUS_BAUD_NOT_CORRECT:
            return DeviceNotConnectedError(
                self._device, f"{what}: tool RS-485 baud rate is not {self._baudrate}", code=code
            )
        return DeviceError(self._device, f"{what}: xArm API code {code} on {where}", code=code)
