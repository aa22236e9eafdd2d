"""Test peer for the Hand-E driver: a simulated gripper behind pymodbus's own RTU server.

- ``SimulatedHandE``: the gripper's register semantics (activation 0->1->3 over a few status
  polls, motion toward rPR at the commanded speed, object contact, faults). It packs and
  unpacks the register bytes itself, independently of the driver's codec.
- ``PtyBridge``: two pseudo-terminal pairs joined by a copy thread. The slave end of a pty
  pair is a real tty that pyserial can open by name (a pty master's ``os.ttyname`` is not),
  so the client opens slave A, the server opens slave B, and the thread copies bytes between
  master A and master B. It can also inject garbage or corrupt replies on the line.
- ``HandEServer``: ``pymodbus.server.ModbusSerialServer`` serving the simulated gripper on
  slave B from a background thread with its own event loop; requests for any other slave id
  get no answer, as on a real RS-485 bus.
- ``FakeXArm``: follows the xArm SDK's documented ``getset_tgpio_modbus_data`` convention
  (``(code, response)``, response from the slave id on, no CRC), backed by a simulated gripper.
"""

from __future__ import annotations

import asyncio
import os
import select
import struct
import threading
import time
import tty
from functools import partial

from pymodbus.exceptions import NoSuchIdException
from pymodbus.server import ModbusSerialServer
from pymodbus.simulator import DataType, SimData, SimDevice

COMMAND_ADDRESS = 0x03E8
STATUS_ADDRESS = 0x07D0
SPEED_MM_S = (20.0, 150.0)  # Hand-E finger speed at rSP = 0x00 and 0xFF


class SimulatedHandE:
    """Register-level model of a Hand-E. Positions are counts: ``open_limit`` = fingers
    fully open (``stroke_m`` apart), ``closed_limit`` = fully closed. Thread-safe."""

    def __init__(
        self,
        *,
        slave_id: int = 9,
        open_limit: int = 3,
        closed_limit: int = 230,
        stroke_m: float = 0.050,
        activation_polls: int = 3,
        object_at: int | None = None,
        activation_fault: bool = False,
        status_lag_polls: int = 0,
    ) -> None:
        self.slave_id = slave_id
        self.open_limit = open_limit
        self.closed_limit = closed_limit
        self.stroke_m = stroke_m
        self.activation_polls = activation_polls
        self.object_at = object_at  # an object between the fingers stops closing here
        self.activation_fault = activation_fault
        # A real gripper may report the previous command's status for a moment after a new
        # command (hence the manual's position request echo): replay it this many polls.
        self.status_lag_polls = status_lag_polls
        self.silent = False  # True: the gripper stops answering
        self.command_writes: list[list[int]] = []
        self.status_reads = 0
        self.activations = 0
        self._lock = threading.Lock()
        self._command = [0, 0, 0]
        self._act = self._gto = self._sta = self._obj = self._flt = 0
        self._position = float(open_limit)
        self._polls_left = 0
        self._stale: list[int] = []
        self._stale_polls = 0
        self._last_s = time.monotonic()

    # -- state set-up for tests ----------------------------------------------------------

    def preset_holding(self, position: int) -> None:
        """Put the gripper in the state of an earlier session: activated, closed on an object."""
        with self._lock:
            self._command = [0x0900, 0xFF, 0xFFFF]
            self._act, self._gto, self._sta, self._obj = 1, 1, 3, 2
            self._position = float(position)

    def inject_fault(self, code: int) -> None:
        """Raise gFLT; a major fault (>= 0x0A) stops the fingers and drops gSTA to 0."""
        with self._lock:
            self._flt = code
            if code >= 0x0A:
                self._sta = self._gto = 0

    @property
    def position(self) -> int:
        with self._lock:
            return round(self._position)

    def count_for_width(self, width_m: float) -> int:
        span = self.closed_limit - self.open_limit
        return round(self.closed_limit - width_m / self.stroke_m * span)

    # -- register access ---------------------------------------------------------------

    def command_registers(self) -> list[int]:
        with self._lock:
            return list(self._command)

    def write_command(self, registers: list[int]) -> None:
        with self._lock:
            self._advance()
            self._stale, self._stale_polls = self._pack_status(), self.status_lag_polls
            self.command_writes.append(list(registers))
            action = registers[0] >> 8
            act, gto = action & 0x01, (action >> 3) & 0x01
            if not act:
                self._act = self._gto = self._sta = self._obj = self._flt = 0
                if gto:
                    self._flt = 0x07  # the activation bit must be set before the action
            elif not self._act or (self._command[0] >> 8) & 0x01 == 0:
                self._act, self._sta, self._gto, self._flt = 1, 1, 0, 0
                self._polls_left = self.activation_polls
                self.activations += 1
            elif gto:
                if self._sta != 3:
                    self._flt = 0x05  # action delayed: activation must complete first
                else:
                    self._gto, self._obj = 1, 0
            self._command = list(registers)

    def status_registers(self) -> list[int]:
        with self._lock:
            self._advance()
            self.status_reads += 1
            if self._sta == 1:
                self._polls_left -= 1
                if self._polls_left <= 0:
                    if self.activation_fault:
                        self._sta, self._flt = 0, 0x0D
                    else:
                        self._sta = 3
            if self._stale_polls > 0:
                self._stale_polls -= 1
                return list(self._stale)
            return self._pack_status()

    def _pack_status(self) -> list[int]:
        """The three status registers for the current state (lock held)."""
        status = (self._obj << 6) | (self._sta << 4) | (self._gto << 3) | self._act
        requested = self._command[1] & 0xFF
        current = 0x10 if self._gto and self._obj == 0 else 0
        position = round(self._position)
        return [status << 8, (self._flt << 8) | requested, (position << 8) | current]

    def _advance(self) -> None:
        """Move the fingers for the time elapsed since the last access (lock held)."""
        now = time.monotonic()
        dt, self._last_s = now - self._last_s, now
        if not (self._act and self._sta == 3 and self._gto and self._obj == 0):
            return
        target = min(max(self._command[1] & 0xFF, self.open_limit), self.closed_limit)
        low, high = SPEED_MM_S
        speed_mm_s = low + (self._command[2] >> 8) / 255 * (high - low)
        counts_per_mm = (self.closed_limit - self.open_limit) / (self.stroke_m * 1000)
        step = speed_mm_s * counts_per_mm * dt
        start = self._position
        if target > start:  # closing: an object between the fingers stops them
            end = min(start + step, target)
            if self.object_at is not None and start <= self.object_at < target:
                if end >= self.object_at:
                    self._position, self._obj = float(self.object_at), 2
                    return
        else:
            end = max(start - step, target)
        self._position = end
        if end == target:
            self._obj = 3


class PtyBridge:
    """Two pty pairs joined by a copy thread: ``client_port`` <-> ``server_port``."""

    def __init__(self) -> None:
        self._client_master, self._client_slave = os.openpty()
        self._server_master, self._server_slave = os.openpty()
        for fd in (self._client_slave, self._server_slave):
            tty.setraw(fd)  # no echo or line editing before the serial ports are opened
        self.client_port = os.ttyname(self._client_slave)
        self.server_port = os.ttyname(self._server_slave)
        self._stop_read, self._stop_write = os.pipe()
        self._lock = threading.Lock()
        self._corrupt_replies = 0
        self._garbage_before_reply = b""
        self.thread = threading.Thread(target=self._run, name="pty-bridge", daemon=True)
        self.thread.start()

    def corrupt_replies(self, count: int) -> None:
        """Flip a bit in each of the next ``count`` chunks sent to the client (bad CRC)."""
        with self._lock:
            self._corrupt_replies = count

    def garbage_before_next_reply(self, data: bytes) -> None:
        """Send ``data`` to the client just before the next reply chunk."""
        with self._lock:
            self._garbage_before_reply = data

    def inject_to_server(self, data: bytes) -> None:
        """Send ``data`` to the server as if it came from the client."""
        os.write(self._server_master, data)

    def _to_client(self, data: bytes) -> bytes:
        with self._lock:
            if self._corrupt_replies:
                self._corrupt_replies -= 1
                data = data[:-1] + bytes([data[-1] ^ 0x5A])
            data, self._garbage_before_reply = self._garbage_before_reply + data, b""
        return data

    def _run(self) -> None:
        sources = [self._client_master, self._server_master, self._stop_read]
        while True:
            readable, _, _ = select.select(sources, [], [])
            if self._stop_read in readable:
                return
            for fd in readable:
                try:
                    data = os.read(fd, 4096)
                except OSError:
                    continue
                if fd == self._server_master:
                    os.write(self._client_master, self._to_client(data))
                else:
                    os.write(self._server_master, data)

    def close(self) -> None:
        os.write(self._stop_write, b"x")
        self.thread.join(timeout=5)
        for fd in (
            self._client_master,
            self._client_slave,
            self._server_master,
            self._server_slave,
            self._stop_read,
            self._stop_write,
        ):
            os.close(fd)


class HandEServer:
    """A simulated Hand-E answering Modbus RTU on ``port`` (use as a context manager)."""

    def __init__(self, gripper: SimulatedHandE | None = None, baudrate: int = 115200) -> None:
        self.gripper = gripper or SimulatedHandE()
        self.baudrate = baudrate
        self.bridge = PtyBridge()
        self.port = self.bridge.client_port
        self._ready = threading.Event()
        self._failure: BaseException | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._stop: asyncio.Event | None = None
        self._thread = threading.Thread(target=self._run, name="hande-server", daemon=True)

    def __enter__(self) -> HandEServer:
        self._thread.start()
        if not self._ready.wait(timeout=5) or self._failure is not None:
            self.__exit__(None, None, None)
            raise RuntimeError(f"simulated Hand-E server did not start: {self._failure!r}")
        return self

    def __exit__(self, *exc_info: object) -> None:
        if self._loop is not None and self._stop is not None and not self._loop.is_closed():
            self._loop.call_soon_threadsafe(self._stop.set)
        self._thread.join(timeout=5)
        self.bridge.close()
        if self._thread.is_alive() or self.bridge.thread.is_alive():
            raise RuntimeError("simulated Hand-E server threads did not stop")

    def _run(self) -> None:
        try:
            asyncio.run(self._serve())
        except BaseException as exc:  # reported to the test thread by __enter__
            self._failure = exc
            self._ready.set()

    async def _serve(self) -> None:
        self._loop = asyncio.get_running_loop()
        self._stop = asyncio.Event()
        registers = [
            SimData(COMMAND_ADDRESS, count=3, values=0, datatype=DataType.REGISTERS),
            SimData(STATUS_ADDRESS, count=3, values=0, datatype=DataType.REGISTERS),
        ]
        gripper = SimDevice(
            id=self.gripper.slave_id, simdata=registers, action=partial(_gripper_action, self)
        )
        # id 0 stands for every other slave id; it spans all addresses (so none is rejected
        # before its action runs) and its action makes the server stay silent.
        others = SimDevice(
            id=0,
            simdata=[SimData(0, count=0x10000, values=0, datatype=DataType.REGISTERS)],
            action=_no_such_slave,
        )
        server = ModbusSerialServer(
            [gripper, others],
            port=self.bridge.server_port,
            baudrate=self.baudrate,
            ignore_missing_devices=True,
        )
        await server.serve_forever(background=True)
        self._ready.set()
        try:
            await self._stop.wait()
        finally:
            await server.shutdown()


async def _gripper_action(
    server: HandEServer,
    function_code: int,
    start_address: int,
    address: int,
    count: int,
    registers: list[int],
    set_values: list[int] | None,
) -> None:
    """pymodbus SimDevice hook: route register accesses through the simulated gripper."""
    gripper = server.gripper
    if gripper.silent:
        raise NoSuchIdException("simulated gripper is silent")
    command_offset = COMMAND_ADDRESS - start_address
    if set_values is not None:
        if COMMAND_ADDRESS <= address < COMMAND_ADDRESS + 3:
            command = gripper.command_registers()
            first = address - COMMAND_ADDRESS
            command[first : first + len(set_values)] = set_values
            gripper.write_command(command[:3])
        return None
    registers[command_offset : command_offset + 3] = gripper.command_registers()
    if address + count > STATUS_ADDRESS:
        status_offset = STATUS_ADDRESS - start_address
        registers[status_offset : status_offset + 3] = gripper.status_registers()
    return None


async def _no_such_slave(*_args: object) -> None:
    raise NoSuchIdException("no device with this slave id on the simulated bus")


class FakeXArm:
    """The slice of ``xarm.wrapper.XArmAPI`` used for the tool RS-485 port.

    ``getset_tgpio_modbus_data(datas, min_res_len=0, host_id=9, ...)`` returns
    ``(code, response)`` like the SDK: ``response`` starts at the slave id and has no CRC;
    ``code`` is 0, or an API code. A gripper that does not answer makes the controller raise
    error C19 and every call return code 1 until ``clean_error()``, as with the real arm.
    ``scripted_codes`` are returned (one per call, before anything is sent) to test codes.
    """

    NOT_CONNECTED = -1
    HAS_ERROR = 1
    MODBUS_ERR_LENG = 23

    def __init__(self, gripper: SimulatedHandE | None = None) -> None:
        self.gripper = gripper or SimulatedHandE()
        self.connected = True
        self.error_code = 0
        self.tgpio_modbus_baud = 2000000
        self.tgpio_modbus_timeout_ms = 0
        self.scripted_codes: list[int] = []
        self.requests: list[list[int]] = []
        self.call_times: list[float] = []

    def set_tgpio_modbus_baudrate(self, baud: int) -> int:
        self.tgpio_modbus_baud = baud
        return 0

    def set_tgpio_modbus_timeout(
        self, timeout: int, is_transparent_transmission: bool = False
    ) -> int:
        self.tgpio_modbus_timeout_ms = timeout
        return 0

    def clean_error(self) -> int:
        self.error_code = 0
        return 0

    def getset_tgpio_modbus_data(
        self,
        datas: list[int],
        min_res_len: int = 0,
        host_id: int = 9,
        is_transparent_transmission: bool = False,
        use_503_port: bool = False,
    ) -> tuple[int, list[int]]:
        self.call_times.append(time.monotonic())
        self.requests.append(list(datas))
        if not self.connected:
            return self.NOT_CONNECTED, []
        if self.scripted_codes:
            return self.scripted_codes.pop(0), []
        response = self._answer(bytes(datas))
        if response is None:
            self.error_code = 19  # C19: end effector communication error
        if self.error_code:
            return self.HAS_ERROR, list(response or [])
        if len(response) < min_res_len:
            return self.MODBUS_ERR_LENG, list(response)
        return 0, list(response)

    def _answer(self, request: bytes) -> bytes | None:
        slave, function = request[0], request[1]
        if slave != self.gripper.slave_id or self.gripper.silent:
            return None
        address, count = struct.unpack(">HH", request[2:6])
        if function == 0x03 and address in (COMMAND_ADDRESS, STATUS_ADDRESS) and count <= 3:
            if address == STATUS_ADDRESS:
                values = self.gripper.status_registers()
            else:
                values = self.gripper.command_registers()
            data = struct.pack(f">{count}H", *values[:count])
            return bytes([slave, function, len(data)]) + data
        if function == 0x10 and address == COMMAND_ADDRESS and count == 3:
            values = list(struct.unpack(">3H", request[7:13]))
            self.gripper.write_command(values)
            return request[:6]
        return bytes([slave, function | 0x80, 0x02])  # illegal data address
