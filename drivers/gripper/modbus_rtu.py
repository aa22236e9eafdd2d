"""The Hand-E over a USB-RS485 adapter: Modbus RTU through pymodbus's ``ModbusSerialClient``.

A ``RegisterTransport`` (``drivers.gripper.transport``). Each attempt waits at most
``timeout_s`` for the reply (the client's own retries are off: the driver counts them), so a
gripper that never answers costs ``(1 + retries) * timeout_s`` per transaction.

pymodbus logs each timeout and retry itself ("No response received after 0 retries, continue
with next request", "Repeating...."); with no logging configured, Python's last-resort handler
would print those lines on the user's terminal. The driver reports every failure as a
``DeviceError`` with the port, baud rate and slave id, so importing this module gives the
``pymodbus`` logger a ``NullHandler`` and stops it propagating; an application that wants
pymodbus's own log adds a handler to ``logging.getLogger("pymodbus")``.
"""

from __future__ import annotations

import inspect
import logging
import os
from collections.abc import Sequence
from typing import Any

from pymodbus.client import ModbusSerialClient
from pymodbus.exceptions import ConnectionException, ModbusException, ModbusIOException

from core.errors import (
    DeviceError,
    DeviceFaultError,
    DeviceNotConnectedError,
    DeviceTimeoutError,
)
from drivers.gripper.transport import exception_text

_PYMODBUS_LOG = logging.getLogger("pymodbus")
_PYMODBUS_LOG.addHandler(logging.NullHandler())
_PYMODBUS_LOG.propagate = False


class ModbusRtuTransport:
    """Modbus RTU through pymodbus's ``ModbusSerialClient`` (USB-RS485 adapter, 8N1).

    The client is given (tests pass one on a pseudo-terminal); ``for_serial_port`` builds
    the real one with ``retries=0`` so that retries are counted by the driver only.
    """

    def __init__(
        self,
        client: ModbusSerialClient,
        *,
        port: str,
        baudrate: int,
        slave_id: int,
        timeout_s: float,
        device: str = "hande",
    ) -> None:
        self._client = client
        self._port = port
        self._slave_id = slave_id
        self._timeout_s = timeout_s
        self._device = device
        self.description = f"serial port {port} at {baudrate} baud 8N1, slave id {slave_id}"
        # pymodbus 3.x renamed the unit keyword ``slave`` to ``device_id``; use whichever
        # the installed client accepts.
        parameters = inspect.signature(client.read_holding_registers).parameters
        self._unit_keyword = "device_id" if "device_id" in parameters else "slave"

    @classmethod
    def for_serial_port(
        cls, port: str, *, baudrate: int, slave_id: int, timeout_s: float, device: str = "hande"
    ) -> ModbusRtuTransport:
        client = ModbusSerialClient(
            port=port,
            baudrate=baudrate,
            bytesize=8,
            parity="N",
            stopbits=1,
            timeout=timeout_s,
            retries=0,
        )
        return cls(
            client,
            port=port,
            baudrate=baudrate,
            slave_id=slave_id,
            timeout_s=timeout_s,
            device=device,
        )

    def open(self) -> None:
        if not os.path.exists(self._port):
            raise DeviceNotConnectedError(
                self._device,
                f"serial port {self._port} not found; is the USB-RS485 adapter plugged in? "
                "Check `ls /dev/serial/by-id` and set `port` to the adapter's stable name",
            )
        if not os.access(self._port, os.R_OK | os.W_OK):
            raise DeviceNotConnectedError(
                self._device,
                f"no permission to open {self._port}; add your user to the 'dialout' group",
            )
        if not self._client.connect():
            raise DeviceNotConnectedError(
                self._device,
                f"cannot open {self._port} (is another program using it?); "
                "check `ls /dev/serial/by-id`",
            )

    def close(self) -> None:
        try:
            self._client.close()
        except (OSError, ModbusException):
            pass  # closing a port that already vanished is not an error

    def read_registers(self, address: int, count: int) -> list[int]:
        what = f"read of {count} registers at 0x{address:04X}"
        reply = self._call(what, self._client.read_holding_registers, address, count=count)
        registers = list(reply.registers)
        if len(registers) != count:
            raise DeviceTimeoutError(
                self._device,
                f"{what}: reply holds {len(registers)} registers on {self.description}",
            )
        return registers

    def write_registers(self, address: int, values: Sequence[int]) -> None:
        what = f"write of {len(values)} registers at 0x{address:04X}"
        self._call(what, self._client.write_registers, address, list(values))

    def _call(self, what: str, method: Any, *args: Any, **kwargs: Any) -> Any:
        kwargs[self._unit_keyword] = self._slave_id
        try:
            reply = method(*args, **kwargs)
        except ConnectionException as exc:
            raise DeviceNotConnectedError(
                self._device, f"{what}: lost {self._port} ({exc}); check the USB-RS485 adapter"
            ) from exc
        except ModbusIOException as exc:
            raise DeviceTimeoutError(
                self._device,
                f"{what}: no valid reply within {self._timeout_s} s on {self.description}",
            ) from exc
        except ModbusException as exc:
            raise DeviceError(self._device, f"{what}: {exc} on {self.description}") from exc
        if isinstance(reply, ModbusIOException):  # older 3.x clients return instead of raise
            raise DeviceTimeoutError(
                self._device,
                f"{what}: no valid reply within {self._timeout_s} s on {self.description}",
            )
        if reply.isError():
            code = int(reply.exception_code)
            raise DeviceFaultError(
                self._device, f"{what}: gripper answered {exception_text(code)}", code=code
            )
        return reply
