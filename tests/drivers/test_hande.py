"""Hand-E driver tests against pymodbus's RTU server on a pty pair and a faithful xArm fake."""

from __future__ import annotations

import threading
import time
from pathlib import Path

import pytest
import yaml

from core.clock import ManualClock
from core.devices import Gripper, GripperObject
from core.errors import (
    DeviceFaultError,
    DeviceNotConnectedError,
    DeviceTimeoutError,
)
from drivers.gripper import HandE, HandEConfig
from drivers.gripper import hande_registers as regs
from drivers.gripper.modbus_rtu import ModbusRtuTransport
from drivers.gripper.transport import XArmToolTransport
from drivers.registry import load_device, load_device_config
from tests.drivers.hande_server import FakeXArm, HandEServer, SimulatedHandE

CONFIG_FILE = Path(__file__).parents[2] / "configs" / "gripper" / "hande.yaml"
ONE_COUNT_M = 0.050 / (230 - 3)  # width resolution of the simulated gripper's calibration


@pytest.fixture(autouse=True)
def no_leaked_threads():
    before = set(threading.enumerate())
    yield
    leaked = [t for t in threading.enumerate() if t not in before and t.is_alive()]
    assert not leaked, f"threads left running: {leaked}"


@pytest.fixture
def server():
    with HandEServer(SimulatedHandE()) as srv:
        yield srv


def config_for(port: str, **overrides) -> HandEConfig:
    # A generous timeout keeps the exact request counts below stable on a loaded machine.
    values = dict(port=port, open_count=3, closed_count=230, timeout_s=0.3, retries=2)
    values.update(overrides)
    return HandEConfig(**values)


# -- register codec, checked against the manual's worked examples ------------------------


def test_status_decoding_matches_manual_example():
    # "09 03 06 B9 00 00 FF BD 00": grip completed, object detected while closing
    raw = regs.decode_status([0xB900, 0x00FF, 0xBD00])
    assert (raw.gACT, raw.gGTO, raw.gSTA, raw.gOBJ) == (1, 1, 3, 2)
    assert (raw.gFLT, raw.gPR, raw.gPO, raw.gCU) == (0, 0xFF, 0xBD, 0)
    # "09 03 02 11 00": activation in progress
    assert regs.decode_status([0x1100, 0, 0]).gSTA == 1
    faulted = regs.decode_status([0x0100, 0x3D00, 0])
    assert (faulted.gFLT, faulted.kFLT) == (0x0D, 0x3)


def test_command_encoding_matches_manual_example():
    # "09 10 03 E8 00 03 06 09 00 00 FF FF FF": close at full speed and force
    assert regs.encode_command(act=True, go=True, position=0xFF, speed=0xFF, force=0xFF) == [
        0x0900,
        0x00FF,
        0xFFFF,
    ]
    assert regs.encode_command(act=True, go=False, position=0, speed=0, force=0) == [0x0100, 0, 0]


def test_speed_force_and_width_mapping():
    assert regs.speed_count(0.020) == 0 and regs.speed_count(0.150) == 255
    assert regs.force_count(20.0) == 0 and regs.force_count(185.0) == 255
    assert regs.force_count(102.5) == 128
    assert regs.position_count(0.050, 3, 230, 0.050) == 3
    assert regs.position_count(0.0, 3, 230, 0.050) == 230
    assert regs.width_from_count(3, 3, 230, 0.050) == pytest.approx(0.050)
    assert regs.width_from_count(255, 3, 230, 0.050) == 0.0  # clamped past the closed count
    with pytest.raises(ValueError, match="speed_m_s"):
        regs.speed_count(0.2)
    with pytest.raises(ValueError, match="force_n"):
        regs.force_count(10.0)
    with pytest.raises(ValueError, match="width_m"):
        regs.position_count(0.06, 3, 230, 0.050)


def test_fault_messages_cover_the_manual_table():
    messages = {code: regs.fault_message(code) for code in range(0x05, 0x10)}
    assert len(set(messages.values())) == len(messages)
    assert all(text.startswith(f"gFLT 0x{code:02X}: ") for code, text in messages.items())
    assert "activation fault" in messages[0x0D]
    assert "overcurrent" in messages[0x0E]
    assert all("re-activate" in messages[code] for code in range(0x0A, 0x10))
    assert "re-activate" not in messages[0x08]
    assert regs.fault_message(0) == ""


# -- behaviour against the pymodbus RTU server -------------------------------------------


def test_activation_runs_reset_then_activate_and_waits_for_gsta_3(server):
    sim = server.gripper
    with HandE.from_config(config_for(server.port)) as gripper:
        assert not gripper.read_status().activated
        gripper.activate()
        status = gripper.read_status()
    assert sim.command_writes == [[0x0000, 0, 0], [0x0100, 0, 0]]
    assert sim.activations == 1
    assert sim.status_reads >= 2 + sim.activation_polls
    assert status.activated and not status.moving and status.fault_code == 0


def test_activate_does_not_reactivate_when_already_activated_and_holding(server):
    sim = server.gripper
    sim.preset_holding(position=150)
    with HandE.from_config(config_for(server.port)) as gripper:
        gripper.activate()
        status = gripper.read_status()
    assert sim.command_writes == []  # nothing written: the fingers keep their grip
    assert status.activated and status.holding
    assert status.width_m == pytest.approx((230 - 150) / (230 - 3) * 0.050)


def test_move_to_width_and_status_decoding(server):
    sim = server.gripper
    with HandE.from_config(config_for(server.port)) as gripper:
        gripper.activate()
        gripper.move(0.020, speed_m_s=0.150, force_n=50.0)
        status = gripper.wait_until_stopped(timeout_s=3.0)
    target = sim.count_for_width(0.020)
    assert sim.command_registers() == [0x0900, target, (255 << 8) | regs.force_count(50.0)]
    assert status.width_m == pytest.approx(0.020, abs=ONE_COUNT_M)
    assert status.object is GripperObject.AT_TARGET
    assert not status.moving and not status.holding


def test_status_is_moving_until_the_position_request_is_echoed():
    sim = SimulatedHandE(status_lag_polls=2)
    with HandEServer(sim) as srv, HandE.from_config(config_for(srv.port)) as gripper:
        gripper.activate()
        gripper.move(0.040, speed_m_s=0.150, force_n=50.0)
        first = gripper.wait_until_stopped(timeout_s=3.0)  # not fooled by the stale status
        gripper.move(0.010, speed_m_s=0.150, force_n=50.0)
        stale = gripper.read_status()  # the device still reports the previous "at target"
        second = gripper.wait_until_stopped(timeout_s=3.0)
    assert first.width_m == pytest.approx(0.040, abs=ONE_COUNT_M)
    assert stale.moving and stale.object is GripperObject.MOVING
    assert second.width_m == pytest.approx(0.010, abs=ONE_COUNT_M)


def test_object_detection_while_closing():
    sim = SimulatedHandE()
    sim.object_at = sim.count_for_width(0.030)
    with HandEServer(sim) as srv, HandE.from_config(config_for(srv.port)) as gripper:
        gripper.activate()
        gripper.move(0.0, speed_m_s=0.150, force_n=100.0)
        status = gripper.wait_until_stopped(timeout_s=3.0)
    assert status.holding and status.object is GripperObject.CONTACT_CLOSING
    assert status.width_m == pytest.approx(0.030, abs=ONE_COUNT_M)


def test_fault_is_decoded_and_cleared_by_reactivation(server):
    with HandE.from_config(config_for(server.port)) as gripper:
        gripper.activate()
        gripper.move(0.045, speed_m_s=0.150, force_n=50.0)
        gripper.wait_until_stopped(timeout_s=3.0)
        server.gripper.inject_fault(0x0E)
        faulted = gripper.read_status()
        gripper.activate()  # a major fault drops gSTA to 0: activate() resets and re-activates
        recovered = gripper.read_status()
    assert faulted.fault_code == 0x0E and "overcurrent" in faulted.fault_message
    assert not faulted.activated
    assert recovered.activated and recovered.fault_code == 0 and recovered.fault_message == ""
    assert not recovered.moving  # the reset cancelled the earlier go-to
    assert server.gripper.activations == 2


def test_activation_fault_raises_with_device_code():
    with (
        HandEServer(SimulatedHandE(activation_fault=True)) as srv,
        HandE.from_config(config_for(srv.port)) as gripper,
    ):
        with pytest.raises(DeviceFaultError, match="activation fault") as info:
            gripper.activate()
    assert info.value.code == 0x0D and info.value.device == "hande"


def test_move_before_activate_is_refused_without_writing(server):
    with HandE.from_config(config_for(server.port)) as gripper:
        with pytest.raises(DeviceFaultError, match="activate") as info:
            gripper.move(0.01, 0.05, 50.0)
        with pytest.raises(ValueError, match="force_n"):
            gripper.move(0.01, 0.05, 500.0)
    assert info.value.code == 0x07
    assert server.gripper.command_writes == []


def test_silent_gripper_times_out_after_retries_then_recovers(server):
    with HandE.from_config(config_for(server.port, timeout_s=0.2, retries=2)) as gripper:
        reads_before = server.gripper.status_reads
        server.gripper.silent = True
        started = time.monotonic()
        with pytest.raises(DeviceTimeoutError) as info:
            gripper.read_status()
        assert time.monotonic() - started < 5.0  # bounded by the attempts, never hangs
        message = str(info.value)
        for expected in (server.port, "115200 baud", "slave id 9", "3 attempt(s)"):
            assert expected in message
        server.gripper.silent = False
        assert gripper.is_connected
        assert gripper.read_status().fault_code == 0
    assert server.gripper.status_reads == reads_before + 1


def test_wrong_slave_id_fails_connect_naming_port_baud_and_slave(server):
    gripper = HandE.from_config(config_for(server.port, slave_id=5, timeout_s=0.1, retries=1))
    with pytest.raises(DeviceTimeoutError) as info:
        gripper.connect()
    message = str(info.value)
    assert server.port in message and "115200 baud" in message and "slave id 5" in message
    assert not gripper.is_connected
    assert server.gripper.status_reads == 0


def test_corrupted_reply_is_retried(server):
    with HandE.from_config(config_for(server.port)) as gripper:
        reads_before = server.gripper.status_reads
        server.bridge.corrupt_replies(1)
        assert gripper.read_status().fault_code == 0
    assert server.gripper.status_reads == reads_before + 2  # the first reply failed its CRC


def test_garbage_on_the_line_is_survived(server):
    with HandE.from_config(config_for(server.port)) as gripper:
        server.bridge.garbage_before_next_reply(b"\xff\x00\xfe\x13\x37")
        assert gripper.read_status().fault_code == 0
        server.bridge.inject_to_server(b"\x09\x10\xff\x00\x42")
        assert gripper.read_status().fault_code == 0


def test_persistent_corruption_raises_a_typed_error(server):
    with HandE.from_config(config_for(server.port, timeout_s=0.2, retries=1)) as gripper:
        server.bridge.corrupt_replies(100)
        with pytest.raises(DeviceTimeoutError, match=r"2 attempt\(s\)"):
            gripper.read_status()
        server.bridge.corrupt_replies(0)
        assert gripper.read_status().fault_code == 0


def test_modbus_exception_reply_is_a_fault_with_its_code(server):
    transport = ModbusRtuTransport.for_serial_port(
        server.port, baudrate=115200, slave_id=9, timeout_s=0.1
    )
    transport.open()
    try:
        with pytest.raises(DeviceFaultError, match="illegal data address") as info:
            transport.read_registers(0x0000, 1)
    finally:
        transport.close()
        transport.close()
    assert info.value.code == 2


# -- bad input ----------------------------------------------------------------------------


def test_missing_serial_port_names_it_and_suggests_by_id():
    port = "/dev/serial/by-id/usb-FTDI_missing-if00-port0"
    gripper = HandE.from_config(HandEConfig(port=port))
    with pytest.raises(DeviceNotConnectedError) as info:
        gripper.connect()
    assert port in str(info.value) and "ls /dev/serial/by-id" in str(info.value)
    assert not gripper.is_connected


@pytest.mark.parametrize(
    ("key", "value"),
    [
        ("transport", "usb"),
        ("port", ""),
        ("baudrate", 1234),
        ("slave_id", 0),
        ("slave_id", 248),
        ("timeout_s", 0.0),
        ("retries", 1.5),
        ("retries", -1),
        ("max_rate_hz", 500.0),
        ("activation_timeout_s", 100.0),
        ("open_count", 255),
        ("closed_count", 3),  # not above open_count=3 below
        ("stroke_m", -0.05),
        ("name", ""),
    ],
)
def test_config_values_out_of_range_name_the_key(key, value):
    values = {"open_count": 3, key: value}
    with pytest.raises(ValueError, match=f"key '{key}'"):
        HandEConfig(**values)


def test_example_config_file_holds_the_defaults():
    assert load_device_config(CONFIG_FILE, backend="real").config == HandEConfig()


def test_xarm_tool_transport_needs_the_arm():
    with pytest.raises(ValueError, match="key 'transport'"):
        HandE.from_config(HandEConfig(transport="xarm_tool"))


# -- lifecycle and pacing -------------------------------------------------------------------


def test_lifecycle(server):
    gripper = HandE.from_config(config_for(server.port))
    assert isinstance(gripper, Gripper)
    with pytest.raises(DeviceNotConnectedError, match="connect"):
        gripper.read_status()
    with pytest.raises(RuntimeError, match="boom"), gripper:
        assert gripper.is_connected
        raise RuntimeError("boom")
    assert not gripper.is_connected
    gripper.disconnect()  # idempotent
    with gripper:  # reconnects after a disconnect
        assert gripper.read_status().width_m == pytest.approx(0.050)


def test_commands_faster_than_max_rate_are_spaced_not_dropped():
    arm = FakeXArm()
    config = HandEConfig(transport="xarm_tool", max_rate_hz=50.0)
    with HandE.from_config(config, arm=arm) as gripper:
        for _ in range(8):
            gripper.read_status()
    assert len(arm.call_times) == 9  # connect's check + 8 reads, none dropped
    gaps = [b - a for a, b in zip(arm.call_times, arm.call_times[1:], strict=False)]
    assert min(gaps) >= 1 / 50.0 - 5e-4


def test_activation_polling_and_the_status_run_on_the_injected_clock():
    """With a ManualClock the activation timeout elapses in clock time, without waiting."""
    arm = FakeXArm(SimulatedHandE(activation_polls=100_000))  # never activates in time
    clock = ManualClock(50.0)
    config = HandEConfig(transport="xarm_tool", activation_timeout_s=1.0)
    with HandE.from_config(config, clock=clock, arm=arm) as gripper:
        with pytest.raises(DeviceTimeoutError, match="within 1.0 s"):
            gripper.activate()
        waited_s = clock.now() - 50.0
        assert 1.0 < waited_s < 1.0 + 0.05  # polls of 20 ms plus the 5 ms command slots
        assert gripper.read_status().t_s == clock.now()


# -- xArm tool RS-485 port --------------------------------------------------------------------


def xarm_gripper(arm: FakeXArm, **overrides) -> HandE:
    values = dict(transport="xarm_tool", open_count=3, closed_count=230, timeout_s=0.1)
    values.update(overrides)
    return HandE.from_config(HandEConfig(**values), arm=arm)


def test_xarm_tool_port_activate_grip_and_status():
    sim = SimulatedHandE()
    sim.object_at = sim.count_for_width(0.025)
    arm = FakeXArm(sim)
    with xarm_gripper(arm) as gripper:
        gripper.activate()
        gripper.move(0.0, speed_m_s=0.150, force_n=185.0)
        status = gripper.wait_until_stopped(timeout_s=3.0)
    assert arm.tgpio_modbus_baud == 115200 and arm.tgpio_modbus_timeout_ms == 100
    assert arm.requests[0] == [0x09, 0x03, 0x07, 0xD0, 0x00, 0x03]  # the manual's status read
    activation = [0x09, 0x10, 0x03, 0xE8, 0x00, 0x03, 0x06, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00]
    assert arm.requests[2:4] == [activation[:7] + [0] * 6, activation]  # clear, then set rACT
    assert status.holding and status.width_m == pytest.approx(0.025, abs=ONE_COUNT_M)


def test_xarm_nonzero_code_is_retried():
    arm = FakeXArm()
    with xarm_gripper(arm) as gripper:
        arm.scripted_codes = [3]  # API code 3: reply timeout
        assert gripper.read_status().fault_code == 0
    assert len(arm.requests) == 3


def test_xarm_silent_gripper_reports_c19_until_cleared():
    arm = FakeXArm()
    with xarm_gripper(arm, retries=1) as gripper:
        arm.gripper.silent = True
        with pytest.raises(DeviceTimeoutError, match="C19") as info:
            gripper.read_status()
        assert "clean_error" in str(info.value) and "slave id 9" in str(info.value)
        assert info.value.code == 1
        arm.gripper.silent = False
        arm.clean_error()
        assert gripper.read_status().fault_code == 0


def test_xarm_disconnected_arm_is_not_retried():
    arm = FakeXArm()
    arm.connected = False
    with pytest.raises(DeviceNotConnectedError, match="xArm is not connected"):
        xarm_gripper(arm).connect()
    arm.connected = True
    with xarm_gripper(arm) as gripper:
        arm.scripted_codes = [-1, 0]
        with pytest.raises(DeviceNotConnectedError) as info:
            gripper.read_status()
    assert info.value.code == -1 and len(arm.requests) == 2


def test_xarm_modbus_exception_reply_is_a_fault():
    transport = XArmToolTransport(FakeXArm(), slave_id=9, baudrate=115200, timeout_s=0.1)
    transport.open()
    with pytest.raises(DeviceFaultError, match="illegal data address") as info:
        transport.read_registers(0x0000, 1)
    assert info.value.code == 2


# -- pymodbus API compatibility ------------------------------------------------------------------


class _Reply:
    registers = [0x3100, 0, 0]

    def isError(self) -> bool:  # noqa: N802 (pymodbus's name)
        return False


class OldStyleClient:
    """A client with the older pymodbus 3.x signature (``slave=``, later renamed ``device_id=``)."""

    def __init__(self) -> None:
        self.calls: list[tuple[int, int, int]] = []

    def read_holding_registers(self, address, count=1, slave=0):
        self.calls.append((address, count, slave))
        return _Reply()


def test_unit_keyword_follows_the_installed_pymodbus_signature():
    client = OldStyleClient()
    transport = ModbusRtuTransport(
        client, port="/dev/null", baudrate=115200, slave_id=9, timeout_s=0.1
    )
    assert transport.read_registers(0x07D0, 3) == [0x3100, 0, 0]
    assert client.calls == [(0x07D0, 3, 9)]


def test_registry_builds_the_real_driver_from_the_example_yaml(server, tmp_path):
    """The example YAML with ``backend: real``, pointed at the pty peer, through the registry."""
    data = yaml.safe_load(CONFIG_FILE.read_text())
    data.update(port=server.port, open_count=3, closed_count=230, timeout_s=0.3)
    path = tmp_path / "hande.yaml"
    path.write_text(yaml.safe_dump(data))
    with load_device(path, backend="real", kind="gripper") as gripper:
        assert isinstance(gripper, HandE)
        gripper.activate()
        gripper.move(0.020, speed_m_s=0.150, force_n=50.0)
        status = gripper.wait_until_stopped(timeout_s=3.0)
    assert status.activated and status.width_m == pytest.approx(0.020, abs=ONE_COUNT_M)
