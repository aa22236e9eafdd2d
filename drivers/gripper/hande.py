"""Robotiq Hand-E parallel gripper over Modbus RTU (USB-RS485 adapter or the xArm tool port).

Implements ``core.devices.Gripper``. Units at this boundary: finger opening in m (0 = closed),
speed in m/s, force in N; the gripper's 0-255 register counts never leave this module.

Behaviour worth knowing:

- ``activate()`` reads the status first and does nothing if the gripper is already activated
  (gACT=1, gSTA=3): re-activating moves the fingers and would drop a held object.
- ``move()`` only sends the go-to command; poll ``read_status()`` (or ``wait_until_stopped``).
- Every register transaction is retried ``retries`` times on timeouts, then raises
  ``DeviceTimeoutError`` naming the port, baud rate and slave id; the driver stays usable.
  Each attempt waits at most ``timeout_s`` (on the xArm tool port: the arm's
  ``io_timeout_s``), so ``connect()`` (one status read) and every call against a silent
  gripper fail within ``(1 + retries)`` attempts; ``activate()`` polls at most
  ``activation_timeout_s`` on the clock.
- The gripper accepts at most 200 commands per second. Transactions faster than
  ``max_rate_hz`` are delayed until their slot, never dropped: a silently dropped gripper
  command is worse than a delay of a few milliseconds.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any, Literal, TypeVar

from core.clock import Clock, MonotonicClock
from core.config import Config, config_dataclass, number
from core.devices import ContextManagedDevice, GripperObject, GripperStatus
from core.errors import DeviceFaultError, DeviceNotConnectedError, DeviceTimeoutError
from drivers.gripper import hande_registers as regs
from drivers.gripper.transport import RegisterTransport, XArmToolTransport

T = TypeVar("T")

_POLL_PERIOD_S = 0.02  # status polling while waiting for activation or motion


@config_dataclass
class HandEConfig(Config):
    """Configuration of the Hand-E driver (configs/gripper/hande.yaml).

    ``transport``: ``"serial"`` (USB-RS485 adapter at ``port``) or ``"xarm_tool"`` (the
    xArm's tool RS-485 port; ``port`` is then unused). ``open_count``/``closed_count``:
    the gPO counts read with the fingers fully open / fully closed on nothing, which map
    to an opening of ``stroke_m`` / 0 m.
    """

    name: str = "hande"
    transport: Literal["serial", "xarm_tool"] = "serial"
    port: str = "/dev/ttyUSB0"
    baudrate: Literal[9600, 19200, 38400, 57600, 115200] = 115200
    slave_id: int = number(1, 247, default=9)
    timeout_s: float = number(0.005, 5.0, default=0.1)
    retries: int = number(0, 10, default=2)
    max_rate_hz: float = number(1.0, 200.0, default=200.0)
    activation_timeout_s: float = number(0.1, 30.0, default=5.0)
    open_count: int = number(0, 254, default=0)
    closed_count: int = number(1, 255, default=255)
    stroke_m: float = number(0.001, 0.2, default=0.050)

    def __post_init__(self) -> None:
        if self.closed_count <= self.open_count:
            raise ValueError(
                f"key 'closed_count': expected more than open_count={self.open_count}, "
                f"got {self.closed_count}"
            )


class HandE(ContextManagedDevice):
    """Robotiq Hand-E gripper; see the module docstring. Thread-safe. ``clock`` stamps the
    status, paces the commands and times the polling (``MonotonicClock`` when None)."""

    def __init__(
        self, config: HandEConfig, transport: RegisterTransport, clock: Clock | None = None
    ) -> None:
        self.config = config
        self.name = config.name
        self._transport = transport
        self._clock = clock if clock is not None else MonotonicClock()
        self._connected = False
        self._activated = False
        self._requested_position: int | None = None  # rPR of the last go-to command
        self._lock = threading.Lock()
        self._next_slot_s = 0.0

    @classmethod
    def from_config(cls, config: HandEConfig, clock: Clock | None = None, arm: Any = None) -> HandE:
        """Build the driver with its real transport (not opened); ``arm`` is the connected
        ``XArmAPI`` (e.g. ``XArm6.api``) when ``config.transport == "xarm_tool"``."""
        transport: RegisterTransport
        if config.transport == "xarm_tool":
            if arm is None:
                raise ValueError("key 'transport': 'xarm_tool' needs the XArmAPI object (arm=)")
            transport = XArmToolTransport(
                arm,
                slave_id=config.slave_id,
                baudrate=config.baudrate,
                timeout_s=config.timeout_s,
                device=config.name,
            )
        else:
            from drivers.gripper.modbus_rtu import ModbusRtuTransport  # pymodbus: only here

            transport = ModbusRtuTransport.for_serial_port(
                config.port,
                baudrate=config.baudrate,
                slave_id=config.slave_id,
                timeout_s=config.timeout_s,
                device=config.name,
            )
        return cls(config, transport, clock)

    # -- lifecycle ---------------------------------------------------------------------

    def connect(self) -> None:
        """Open the link and check that the gripper answers (does not move it)."""
        if self._connected:
            return
        self._transport.open()
        self._connected = True
        try:
            self._read_raw()
        except BaseException:
            self.disconnect()
            raise

    def disconnect(self) -> None:
        if not self._connected:
            return
        self._connected = False
        self._activated = False
        self._requested_position = None
        self._transport.close()

    @property
    def is_connected(self) -> bool:
        return self._connected

    # -- Gripper -----------------------------------------------------------------------

    def activate(self) -> None:
        """Activate the gripper unless it already is (then nothing is written, so a held
        object stays held). Blocks until gSTA=3 or ``activation_timeout_s``."""
        raw = self._read_raw()
        if raw.gACT == 1 and raw.gSTA == regs.GSTA_ACTIVATED:
            self._activated = True
            return
        if not (raw.gACT == 1 and raw.gSTA == regs.GSTA_ACTIVATING):
            # A rising edge of rACT activates and clears faults: clear first, then set.
            self._requested_position = None  # the reset cancels any go-to command
            self._write_command(act=False, go=False, position=0, speed=0, force=0)
            self._write_command(act=True, go=False, position=0, speed=0, force=0)
        deadline = self._clock.now() + self.config.activation_timeout_s
        while True:
            raw = self._read_raw()
            if raw.gACT == 1 and raw.gSTA == regs.GSTA_ACTIVATED:
                self._activated = True
                return
            if raw.gFLT >= regs.MAJOR_FAULT_MIN:
                raise DeviceFaultError(
                    self.name,
                    f"activation failed: {regs.fault_message(raw.gFLT, raw.kFLT)}",
                    code=raw.gFLT,
                )
            if self._clock.now() > deadline:
                raise DeviceTimeoutError(
                    self.name,
                    f"activation did not complete within {self.config.activation_timeout_s} s "
                    f"(gSTA={raw.gSTA}); check that nothing blocks the fingers",
                )
            self._clock.sleep(_POLL_PERIOD_S)

    def move(self, width_m: float, speed_m_s: float, force_n: float) -> None:
        """Send the fingers toward an opening of ``width_m`` (m) at ``speed_m_s`` (m/s,
        0.020-0.150) with ``force_n`` (N, 20-185). Returns once the command is accepted."""
        cfg = self.config
        position = regs.position_count(width_m, cfg.open_count, cfg.closed_count, cfg.stroke_m)
        speed = regs.speed_count(speed_m_s)
        force = regs.force_count(force_n)
        if not self._activated:
            raise DeviceFaultError(
                self.name, "not activated: call activate() before move()", code=0x07
            )
        self._write_command(act=True, go=True, position=position, speed=speed, force=force)
        self._requested_position = position

    def read_status(self) -> GripperStatus:
        """One status reading. Faults are reported in the status, not raised."""
        raw = self._read_raw()
        t_s = self._clock.now()
        cfg = self.config
        # Until the position request echo gPR matches the last go-to command, the status
        # still describes the previous one. The manual says to ignore gOBJ when gGTO == 0
        # (no go-to in progress): report AT_TARGET then, i.e. stopped, no object detected.
        if self._requested_position not in (None, raw.gPR):
            obj = GripperObject.MOVING
        elif raw.gGTO == 0:
            obj = GripperObject.AT_TARGET
        else:
            obj = GripperObject(raw.gOBJ)
        return GripperStatus(
            t_s=t_s,
            activated=raw.gACT == 1 and raw.gSTA == regs.GSTA_ACTIVATED,
            moving=raw.gSTA == regs.GSTA_ACTIVATING or obj is GripperObject.MOVING,
            object=obj,
            width_m=regs.width_from_count(raw.gPO, cfg.open_count, cfg.closed_count, cfg.stroke_m),
            fault_code=raw.gFLT,
            fault_message=regs.fault_message(raw.gFLT, raw.kFLT),
        )

    def wait_until_stopped(self, timeout_s: float) -> GripperStatus:
        """Poll until the fingers stop (target reached or object met); returns that status."""
        deadline = self._clock.now() + timeout_s
        while True:
            status = self.read_status()
            if not status.moving:
                return status
            if self._clock.now() > deadline:
                raise DeviceTimeoutError(
                    self.name, f"fingers still moving after {timeout_s} s (at {status.width_m} m)"
                )
            self._clock.sleep(_POLL_PERIOD_S)

    # -- registers ---------------------------------------------------------------------

    def _read_raw(self) -> regs.RawStatus:
        registers = self._transact(
            "status read",
            lambda: self._transport.read_registers(regs.STATUS_ADDRESS, regs.REGISTER_COUNT),
        )
        return regs.decode_status(registers)

    def _write_command(self, *, act: bool, go: bool, position: int, speed: int, force: int) -> None:
        values = regs.encode_command(act=act, go=go, position=position, speed=speed, force=force)
        self._transact(
            "command write",
            lambda: self._transport.write_registers(regs.COMMAND_ADDRESS, values),
        )

    def _transact(self, what: str, operation: Callable[[], T]) -> T:
        """Run one register transaction, paced to ``max_rate_hz`` and retried on timeouts."""
        if not self._connected:
            raise DeviceNotConnectedError(self.name, f"{what}: not connected; call connect()")
        attempts = 1 + self.config.retries
        with self._lock:
            failures: list[DeviceTimeoutError] = []
            for _ in range(attempts):
                self._wait_for_slot()
                try:
                    return operation()
                except DeviceTimeoutError as exc:
                    failures.append(exc)
        last = failures[-1]
        raise DeviceTimeoutError(
            self.name,
            f"{what}: no valid answer after {attempts} attempt(s) of {self.config.timeout_s} s;"
            f" last: {last.message}. Check the baud rate and slave id (Hand-E default: 115200 "
            "baud 8N1, slave id 9), the RS-485 wiring and the gripper's 24 V supply",
            code=last.code,
        ) from last

    def _wait_for_slot(self) -> None:
        now = self._clock.now()
        if now < self._next_slot_s:
            self._clock.sleep(self._next_slot_s - now)
            now = self._clock.now()
        self._next_slot_s = now + 1.0 / self.config.max_rate_hz
