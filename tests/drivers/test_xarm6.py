"""The xArm6 driver against a faithful fake of the SDK's XArmAPI (tests/drivers/fake_xarm_api.py),
and against the real XArmAPI where no network is needed (not connected, loopback refused)."""

from __future__ import annotations

import dataclasses
import inspect
import math
import signal
import socket
import subprocess
import sys
import textwrap
import threading
import time

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from core.clock import ManualClock
from core.config import CONFIG_ROOT
from core.devices import Arm, ArmMode, ArmState, Pose, Twist
from core.errors import DeviceFaultError, DeviceNotConnectedError, DeviceTimeoutError
from core.spatial import rotation_from_rpy, tilt_of_rotation
from drivers.arm import SafetyEnvelope, TcpConfig, XArm6, XArm6Config
from drivers.registry import load_device, load_device_config
from tests.drivers.fake_xarm_api import FakeXArmAPI

CONFIG_FILE = CONFIG_ROOT / "robot" / "xarm6.yaml"
TOL = 1e-9
ENV = SafetyEnvelope(
    x_min_m=0.2, x_max_m=0.5, y_min_m=-0.2, y_max_m=0.2, z_min_m=0.05, z_max_m=0.4,
    max_linear_speed_m_s=0.1, max_angular_speed_rad_s=0.5, max_step_m=0.002, max_step_rad=0.01,
    max_tilt_rad=0.35,
)  # fmt: skip
TCP = TcpConfig(
    offset_x_m=0.0, offset_y_m=0.01, offset_z_m=0.205, offset_roll_rad=0.0,
    offset_pitch_rad=0.0, offset_yaw_rad=0.5, load_mass_kg=1.25, load_com_x_m=0.0,
    load_com_y_m=0.0, load_com_z_m=0.07,
)  # fmt: skip
CONFIG = XArm6Config(
    ip="192.168.1.185", servo_rate_hz=100, velocity_timeout_s=0.2, move_timeout_s=30.0,
    tcp=TCP, envelope=ENV,
)  # fmt: skip
STARTUP = ["motion_enable", "set_mode", "set_state"]
HOME = Pose((0.3, 0.0, 0.2), (math.pi, 0.0, 0.0))


def make(connect: bool = True, **hooks) -> tuple[XArm6, FakeXArmAPI, ManualClock]:
    """A driver over a fake with the given test hooks set (e.g. ``sticky_error=True``)."""
    fake = FakeXArmAPI(CONFIG.ip, is_radian=True, do_not_open=True)
    for hook, value in hooks.items():
        setattr(fake, hook, value)
    clock = ManualClock(100.0)
    arm = XArm6(CONFIG, fake, clock=clock)
    if connect:
        arm.connect()
    return arm, fake, clock


def names_since(fake: FakeXArmAPI, start: int) -> list[str]:
    return [c.name for c in fake.calls[start:]]


def state_changing(fake: FakeXArmAPI, start: int = 0) -> list[tuple[str, object]]:
    """(name, argument) of the calls that enable the motors or set the mode or state."""
    out: list[tuple[str, object]] = []
    for call in fake.calls[start:]:
        if call.name == "motion_enable":
            out.append((call.name, call.kwargs["enable"]))
        elif call.name in ("set_mode", "set_state"):
            out.append((call.name, call.args[0]))
    return out


# --------------------------------------------------------------------- start-up and modes


def test_connect_runs_the_documented_start_up_then_sets_the_tcp():
    arm, fake, _ = make()
    assert isinstance(arm, Arm) and arm.is_connected
    assert names_since(fake, 0) == [
        "register_error_warn_changed_callback", "connect", "set_timeout", "get_err_warn_code",
        "motion_enable", "set_mode", "set_state", "set_tcp_offset", "set_tcp_load",
    ]  # fmt: skip
    assert fake.named("set_timeout")[0].args == (CONFIG.io_timeout_s,)
    assert state_changing(fake) == [("motion_enable", True), ("set_mode", 0), ("set_state", 0)]
    assert fake.mode == 0 and fake.state == 2
    np.testing.assert_allclose(fake.tcp_offset, [0.0, 10.0, 205.0, 0.0, 0.0, 0.5])  # mm, rad
    assert fake.named("set_tcp_offset")[0].kwargs == {"is_radian": True, "wait": True}
    assert fake.tcp_load[0] == 1.25
    np.testing.assert_allclose(fake.tcp_load[1], [0.0, 0.0, 70.0])  # mm


def test_each_mode_switch_re_runs_enable_mode_state_and_commands_go_in_their_mode():
    arm, fake, clock = make()
    start = len(fake.calls)
    arm.servo_pose(HOME)
    clock.advance(0.01)
    arm.servo_pose(HOME)  # same mode: no re-arm
    arm.move_velocity(Twist((0.01, 0.0, 0.0)), 0.1)
    arm.move_to(HOME, 0.05)
    assert names_since(fake, start) == [
        *STARTUP, "get_position", "set_servo_cartesian", "set_servo_cartesian",
        *STARTUP, "get_position", "vc_set_cartesian_velocity",
        *STARTUP, "set_position",
    ]  # fmt: skip
    assert [c.args[0] for c in fake.named("set_mode")] == [0, 1, 5, 0]
    assert all(c.mode == 1 for c in fake.named("set_servo_cartesian"))
    assert all(c.mode == 5 for c in fake.named("vc_set_cartesian_velocity"))
    assert all(c.mode == 0 for c in fake.named("set_position"))


def test_velocity_commands_always_carry_a_positive_watchdog_duration():
    arm, fake, _ = make()
    arm.move_velocity(Twist((0.01, 0.0, 0.0)), 0.05)
    arm.move_velocity(Twist((0.01, 0.0, 0.0)), 60.0)  # capped at velocity_timeout_s
    assert [c.kwargs["duration"] for c in fake.named("vc_set_cartesian_velocity")] == [0.05, 0.2]
    for bad in (0.0, -1.0, math.nan, math.inf):
        with pytest.raises(ValueError, match="duration_s"):
            arm.move_velocity(Twist((0.01, 0.0, 0.0)), bad)
    assert len(fake.named("vc_set_cartesian_velocity")) == 2


def test_velocity_mode_is_refused_when_the_firmware_ignores_the_duration():
    arm, fake, _ = make()
    fake.version_number = (1, 7, 9)
    with pytest.raises(DeviceFaultError, match="1.8.0"):
        arm.move_velocity(Twist((0.01, 0.0, 0.0)), 0.1)
    assert fake.named("vc_set_cartesian_velocity") == []


def test_stop_zeroes_velocity_in_mode_5_and_stops_and_re_arms_otherwise():
    arm, fake, _ = make()
    arm.move_velocity(Twist((0.01, 0.0, 0.0)), 0.1)
    arm.stop()
    zero = fake.named("vc_set_cartesian_velocity")[-1]
    assert zero.args[0] == [0.0] * 6 and zero.kwargs["duration"] == 0.2
    arm.servo_pose(HOME)
    start = len(fake.calls)
    arm.stop()
    assert state_changing(fake, start) == [
        ("set_state", 4),
        ("motion_enable", True),
        ("set_mode", 1),
        ("set_state", 0),
    ]
    assert fake.state == 2 and fake.mode == 1


def test_move_to_waits_with_the_configured_timeout():
    arm, fake, _ = make()
    arm.move_to(HOME, 0.05)
    arm.move_to(HOME, 0.05, wait=False)
    waited, unwaited = fake.named("set_position")
    assert (waited.kwargs["wait"], waited.kwargs["timeout"]) == (True, 30.0)
    assert (unwaited.kwargs["wait"], unwaited.kwargs["timeout"]) == (False, None)


# --------------------------------------------------------------------- units


def test_readings_convert_mm_to_m_and_keep_radians():
    arm, fake, clock = make()
    fake.pose = [312.5, -20.25, 150.0, math.pi - 0.1, 0.05, 0.3]
    state = arm.read_status()
    assert state.tcp.xyz_m == pytest.approx((0.3125, -0.02025, 0.15), abs=1e-12)
    assert state.tcp.rpy_rad == pytest.approx((math.pi - 0.1, 0.05, 0.3), abs=1e-6)
    assert state.joints_rad == pytest.approx(tuple(fake.joints[:6]), abs=1e-6)
    assert (state.t_s, state.mode, state.state, state.error_code) == (
        clock.now(),
        ArmMode.POSITION,
        ArmState.READY,
        0,
    )
    assert fake.named("get_position")[-1].kwargs == {"is_radian": True}


def test_without_the_ft_sensor_the_status_has_no_force_and_the_sensor_is_never_asked():
    arm, fake, _ = make()
    assert arm.read_status().external_force_n is None
    assert not fake.named("set_ft_sensor_enable") and not fake.named("get_ft_sensor_data")


def ft_arm() -> tuple[XArm6, FakeXArmAPI]:
    fake = FakeXArmAPI(CONFIG.ip, is_radian=True, do_not_open=True)
    arm = XArm6(dataclasses.replace(CONFIG, ft_sensor=True), fake, clock=ManualClock(100.0))
    arm.connect()
    return arm, fake


def test_the_ft_sensor_is_enabled_before_arming_and_its_force_is_turned_into_b():
    arm, fake = ft_arm()
    names = names_since(fake, 0)
    assert fake.ft_enabled and names.index("set_ft_sensor_enable") < names.index("motion_enable")
    fake.pose = [300.0, 0.0, 200.0, math.pi - 0.1, 0.05, 0.3]
    fake.ft_wrench = [1.0, 2.0, -3.0, 0.1, 0.2, 0.3]
    force = arm.read_status().external_force_n
    flange = Rotation.from_euler("xyz", fake.pose[3:]) * Rotation.from_euler("z", 0.5).inv()
    assert force == pytest.approx(tuple(flange.apply([1.0, 2.0, -3.0])), abs=1e-5)  # 6-decimal pose


def test_a_push_up_on_a_tool_pointing_down_reads_up_in_b():
    fake = FakeXArmAPI(CONFIG.ip, is_radian=True, do_not_open=True)
    tcp = dataclasses.replace(TCP, offset_yaw_rad=0.0)
    config = dataclasses.replace(CONFIG, tcp=tcp, ft_sensor=True)
    arm = XArm6(config, fake, clock=ManualClock(100.0))
    arm.connect()
    fake.pose = [300.0, 0.0, 200.0, math.pi, 0.0, 0.0]  # the flange's z points down
    fake.ft_wrench = [0.0, 0.0, -4.0, 0.0, 0.0, 0.0]  # along -z of the flange: up
    assert arm.read_status().external_force_n == pytest.approx((0.0, 0.0, 4.0), abs=1e-5)


def test_a_failed_ft_reading_raises_naming_the_call():
    arm, fake = ft_arm()
    fake.fail_next("get_ft_sensor_data", 11)
    with pytest.raises(DeviceFaultError, match="get_ft_sensor_data"):
        arm.read_status()


def test_commands_convert_m_to_mm_and_round_trip():
    arm, fake, _ = make()
    fake.pose = [312.5, -20.25, 150.0, math.pi - 0.1, 0.05, 0.3]
    arm.servo_pose(arm.read_status().tcp)  # hold: the command is the reading
    np.testing.assert_allclose(fake.named("set_servo_cartesian")[-1].sent, fake.pose, atol=1e-6)
    target = Pose((0.25, 0.1, 0.3), (math.pi, 0.1, -0.2))
    arm.move_to(target, 0.05)
    sent = fake.named("set_position")[-1]
    np.testing.assert_allclose(sent.sent["pose"], [250.0, 100.0, 300.0, math.pi, 0.1, -0.2])
    assert sent.kwargs["speed"] == pytest.approx(50.0)  # mm/s
    assert arm.read_status().tcp.xyz_m == pytest.approx(target.xyz_m, abs=1e-9)
    arm.move_velocity(Twist((0.01, -0.02, 0.03), (0.0, 0.0, 0.1)), 0.1)
    speeds, duration = fake.named("vc_set_cartesian_velocity")[-1].sent
    np.testing.assert_allclose(speeds, [10.0, -20.0, 30.0, 0.0, 0.0, 0.1])  # mm/s, rad/s
    assert duration == 0.1


def test_the_api_default_unit_does_not_matter_every_call_says_radians():
    """The SDK's default is degrees (is_radian=False); the driver passes is_radian=True on
    every call, so it sees and sends the same values whatever the constructor said."""
    results = []
    for default_is_radian in (False, True):
        fake = FakeXArmAPI(CONFIG.ip, is_radian=default_is_radian, do_not_open=True)
        fake.pose = [312.5, -20.25, 150.0, math.pi - 0.1, 0.05, 0.3]
        arm = XArm6(CONFIG, fake, clock=ManualClock(100.0))
        arm.connect()
        state = arm.read_status()
        arm.servo_pose(Pose((0.313, -0.02, 0.151), (math.pi, 0.06, 0.29)))
        arm.move_to(HOME, 0.05)
        results.append((state, fake.tcp_offset, [c.sent for c in fake.calls if c.sent]))
    assert results[0] == results[1]


# --------------------------------------------------------------------- envelope


@st.composite
def targets(draw) -> Pose:
    return Pose(
        tuple(draw(st.floats(-1.0, 1.0)) for _ in range(3)),
        tuple(draw(st.floats(-4.0, 4.0)) for _ in range(3)),
    )


@settings(max_examples=40, deadline=None)
@given(
    stream=st.lists(st.tuples(targets(), st.floats(0.0, 0.05)), min_size=1, max_size=25),
    start=st.tuples(
        st.floats(0.21, 0.49), st.floats(-0.19, 0.19), st.floats(0.06, 0.39), st.floats(0.0, 0.3)
    ),
)
def test_no_servo_command_ever_leaves_the_envelope(stream, start):
    arm, fake, clock = make()
    fake.pose = [start[0] * 1e3, start[1] * 1e3, start[2] * 1e3, math.pi, start[3], 0.0]
    previous = np.array(fake.pose)
    elapsed = 1.0 / CONFIG.servo_rate_hz
    for target, dt in stream:
        arm.servo_pose(target)
        sent = np.array(fake.named("set_servo_cartesian")[-1].sent)
        position, last_position = sent[:3] / 1e3, previous[:3] / 1e3
        assert np.all(position >= ENV.box_min_m - TOL) and np.all(position <= ENV.box_max_m + TOL)
        step_m = min(ENV.max_step_m, ENV.max_linear_speed_m_s * elapsed)
        assert np.linalg.norm(position - last_position) <= step_m + TOL
        rotation, last_rotation = rotation_from_rpy(sent[3:]), rotation_from_rpy(previous[3:])
        assert tilt_of_rotation(rotation) <= ENV.max_tilt_rad + TOL
        step_rad = min(ENV.max_step_rad, ENV.max_angular_speed_rad_s * elapsed)
        assert (rotation * last_rotation.inv()).magnitude() <= step_rad + 1e-6  # SDK rounding
        previous = sent
        clock.advance(dt)
        elapsed = dt


@settings(max_examples=40, deadline=None)
@given(target=targets(), speed=st.floats(1e-3, 10.0))
def test_no_position_move_ever_leaves_the_envelope(target, speed):
    arm, fake, _ = make()
    arm.move_to(target, speed)
    sent = fake.named("set_position")[-1]
    position = np.array(sent.sent["pose"][:3]) / 1e3
    assert np.all(position >= ENV.box_min_m - TOL) and np.all(position <= ENV.box_max_m + TOL)
    assert tilt_of_rotation(rotation_from_rpy(sent.sent["pose"][3:])) <= ENV.max_tilt_rad + TOL
    assert 0 < sent.kwargs["speed"] <= ENV.max_linear_speed_m_s * 1e3 + TOL


@settings(max_examples=40, deadline=None)
@given(
    start=st.tuples(
        st.floats(0.2, 0.5), st.floats(-0.2, 0.2), st.floats(0.05, 0.4), st.floats(0.0, 0.35)
    ),
    linear=st.tuples(*(st.floats(-1.0, 1.0),) * 3),
    angular=st.tuples(*(st.floats(-3.0, 3.0),) * 3),
    duration=st.floats(0.001, 5.0),
)
def test_no_velocity_command_ever_leaves_the_envelope(start, linear, angular, duration):
    arm, fake, _ = make()
    fake.pose = [start[0] * 1e3, start[1] * 1e3, start[2] * 1e3, math.pi, start[3], 0.0]
    arm.move_velocity(Twist(linear, angular), duration)
    speeds, sent_duration = fake.named("vc_set_cartesian_velocity")[-1].sent
    v, w = np.array(speeds[:3]) / 1e3, np.array(speeds[3:])
    assert 0 < sent_duration <= CONFIG.velocity_timeout_s
    assert np.linalg.norm(v) <= ENV.max_linear_speed_m_s + TOL
    assert np.linalg.norm(w) <= ENV.max_angular_speed_rad_s + TOL
    after = np.array(fake.pose[:3]) / 1e3 + v * sent_duration
    assert np.all(after >= ENV.box_min_m - 1e-8) and np.all(after <= ENV.box_max_m + 1e-8)
    rotation = rotation_from_rpy(fake.pose[3:])
    turned = Rotation.from_rotvec(w * sent_duration) * rotation
    assert tilt_of_rotation(turned) <= ENV.max_tilt_rad + 1e-6


def test_servo_stream_is_refused_from_outside_the_envelope_until_moved_inside():
    arm, fake, _ = make()
    fake.pose = [300.0, 0.0, 600.0, math.pi, 0.0, 0.0]  # 20 cm above the box
    with pytest.raises(DeviceFaultError, match="outside the safety envelope"):
        arm.servo_pose(HOME)
    assert fake.named("set_servo_cartesian") == []
    arm.move_to(HOME, 0.05)
    arm.servo_pose(HOME)
    assert len(fake.named("set_servo_cartesian")) == 1


def test_non_finite_targets_are_rejected_before_reaching_the_sdk():
    arm, fake, _ = make()
    start = len(fake.calls)
    with pytest.raises(ValueError, match="target"):
        arm.servo_pose(Pose((0.3, math.nan, 0.2), (math.pi, 0.0, 0.0)))
    with pytest.raises(ValueError, match="speed_m_s"):
        arm.move_to(HOME, 0.0)
    with pytest.raises(ValueError, match="twist"):
        arm.move_velocity(Twist((math.inf, 0.0, 0.0)), 0.1)
    assert fake.calls[start:] == []


# --------------------------------------------------------------------- faults


def test_error_callback_latches_a_fault_and_stops_the_arm():
    arm, fake, _ = make()
    arm.servo_pose(HOME)
    start = len(fake.calls)
    fake.inject_error(31)  # C31: collision caused abnormal current
    assert state_changing(fake, start) == [("set_state", 4)]
    assert isinstance(arm.fault, DeviceFaultError) and arm.fault.code == 31
    assert "Collision" in arm.fault.message
    sent = len(fake.named("set_servo_cartesian"))
    with pytest.raises(DeviceFaultError, match="clear_fault") as raised:
        arm.servo_pose(HOME)
    assert raised.value.code == 31
    with pytest.raises(DeviceFaultError):
        arm.move_to(HOME, 0.05)
    assert len(fake.named("set_servo_cartesian")) == sent and len(fake.named("set_position")) == 0
    assert arm.read_status().error_code == 31  # reading still works


def test_a_warning_is_a_fault_too():
    arm, fake, _ = make()
    fake.inject_warning(14)  # W14: no solution
    assert arm.fault.code == 14 and "no solution" in arm.fault.message
    with pytest.raises(DeviceFaultError):
        arm.move_velocity(Twist((0.01, 0.0, 0.0)), 0.1)


def test_clear_fault_runs_the_documented_recovery():
    arm, fake, _ = make()
    fake.inject_error(22)
    start = len(fake.calls)
    arm.clear_fault()
    assert names_since(fake, start) == [
        "clean_error", "clean_warn", "get_err_warn_code",
        *STARTUP, "set_tcp_offset", "set_tcp_load",
    ]  # fmt: skip
    assert state_changing(fake, start) == [
        ("motion_enable", True),
        ("set_mode", 0),
        ("set_state", 0),
    ]
    assert arm.fault is None and fake.error_code == 0 and fake.state == 2
    arm.servo_pose(HOME)
    assert len(fake.named("set_servo_cartesian")) == 1


def test_clear_fault_raises_while_the_cause_remains():
    arm, fake, _ = make(sticky_error=True)
    fake.inject_error(1)  # C1: emergency stop button pushed in
    with pytest.raises(DeviceFaultError, match="persists") as raised:
        arm.clear_fault()
    assert raised.value.code == 1 and "Emergency Stop" in raised.value.message
    assert (
        arm.fault is not None and fake.named("motion_enable")[-1] is fake.named("motion_enable")[0]
    )


def test_a_non_zero_servo_code_raises_fault_with_the_code_and_stops():
    arm, fake, _ = make()
    arm.servo_pose(HOME)
    fake.fail_next("set_servo_cartesian", 12)
    with pytest.raises(DeviceFaultError, match="parameter error") as raised:
        arm.servo_pose(HOME)
    assert raised.value.code == 12
    assert fake.calls[-1].name == "set_state" and fake.calls[-1].args == (4,)
    assert arm.fault is not None and arm.fault.code == 12


def test_code_1_names_the_controller_error_even_before_its_report_arrives():
    arm, fake, _ = make()
    arm.servo_pose(HOME)
    fake.inject_error(22, notify=False)  # C22: self-collision, report not yet received
    with pytest.raises(DeviceFaultError, match="C22: Self-Collision") as raised:
        arm.servo_pose(HOME)
    assert raised.value.code == 1


def test_timeouts_raise_timeout_errors_and_stop_without_latching():
    arm, fake, _ = make()
    fake.fail_next("set_position", 100)
    with pytest.raises(DeviceTimeoutError, match="motion to finish") as raised:
        arm.move_to(HOME, 0.05)
    assert raised.value.code == 100 and arm.fault is None
    assert fake.calls[-1].name == "set_state" and fake.calls[-1].args == (4,)
    arm.move_to(HOME, 0.05)  # re-arms, then moves
    assert state_changing(fake)[-3:] == [("motion_enable", True), ("set_mode", 0), ("set_state", 0)]


def test_emergency_stop_latches_a_fault_until_cleared():
    arm, fake, _ = make()
    arm.emergency_stop()
    assert fake.calls[-1].name == "emergency_stop" and fake.state == 4
    with pytest.raises(DeviceFaultError, match="emergency stop"):
        arm.servo_pose(HOME)
    arm.clear_fault()
    arm.servo_pose(HOME)


def test_emergency_stop_reports_when_the_controller_does_not_stop():
    arm, fake, _ = make(ignore_stop=True)
    with pytest.raises(DeviceFaultError, match="not confirmed"):
        arm.emergency_stop()


def test_a_fault_present_at_connect_is_latched_and_the_arm_left_unarmed():
    arm, fake, _ = make(connect=False)
    fake.inject_error(31, notify=False)  # present in the controller before we connect
    arm.connect()
    assert arm.is_connected and arm.fault is not None and arm.fault.code == 31
    assert fake.named("motion_enable") == [] and fake.named("set_tcp_offset") == []
    with pytest.raises(DeviceFaultError):
        arm.servo_pose(HOME)
    arm.clear_fault()
    assert fake.tcp_offset is not None and fake.state == 2


# --------------------------------------------------------------------- connection


def test_not_connected_calls_raise_not_connected():
    arm, fake, _ = make(connect=False)
    for call in (
        arm.read_status,
        arm.stop,
        arm.emergency_stop,
        arm.clear_fault,
        lambda: arm.servo_pose(HOME),
    ):
        with pytest.raises(DeviceNotConnectedError, match="connect"):
            call()
    assert fake.calls == []


def test_getters_returning_the_not_connected_string_raise_not_connected():
    arm, fake, _ = make()
    fake.fail_next("get_position", -1)  # the link dropped between our check and the call
    with pytest.raises(DeviceNotConnectedError, match="API code -1") as raised:
        arm.read_status()
    assert raised.value.code == -1


def test_connect_refused_raises_not_connected_and_releases_the_callback():
    arm, fake, _ = make(connect=False, refuse_connection=True)
    with pytest.raises(DeviceNotConnectedError, match="192.168.1.185"):
        arm.connect()
    assert names_since(fake, len(fake.calls) - 2) == [
        "release_error_warn_changed_callback",
        "disconnect",
    ]
    assert fake._callbacks == []


def test_disconnect_stops_releases_and_is_idempotent_and_the_context_manager_cleans_up():
    arm, fake, _ = make(connect=False)
    with pytest.raises(RuntimeError), arm:
        assert arm.is_connected
        raise RuntimeError("boom")
    assert not arm.is_connected and fake._callbacks == []
    assert names_since(fake, len(fake.calls) - 3) == [
        "set_state",
        "release_error_warn_changed_callback",
        "disconnect",
    ]
    arm.disconnect()
    assert not arm.is_connected


def test_a_lost_link_is_reported_as_not_connected():
    arm, fake, _ = make()
    fake.drop_connection()
    with pytest.raises(DeviceNotConnectedError):
        arm.servo_pose(HOME)
    arm.disconnect()  # never raises


# --------------------------------------------------------------------- the real SDK


def test_from_config_builds_an_unconnected_real_xarm_api_in_radians():
    from xarm.wrapper import XArmAPI

    arm = XArm6.from_config(CONFIG)
    assert isinstance(arm.api.wrapped, XArmAPI) and arm.api.default_is_radian is True
    assert not arm.is_connected
    with pytest.raises(DeviceNotConnectedError):
        arm.read_status()
    arm.disconnect()


def test_the_fake_matches_the_real_sdk_when_not_connected():
    from xarm.wrapper import XArmAPI

    real = XArmAPI(CONFIG.ip, is_radian=True, do_not_open=True)
    fake = FakeXArmAPI(CONFIG.ip, is_radian=True, do_not_open=True)
    calls = [
        ("get_position", (), {"is_radian": True}),
        ("get_servo_angle", (), {"is_radian": True}),
        ("get_err_warn_code", (), {}),
        ("motion_enable", (), {"enable": True}),
        ("set_mode", (1,), {}),
        ("set_state", (0,), {}),
        ("clean_error", (), {}),
        ("clean_warn", (), {}),
        ("set_tcp_offset", ([0.0] * 6,), {"is_radian": True, "wait": True}),
        ("set_tcp_load", (1.0, [0.0, 0.0, 50.0]), {"wait": True}),
        ("set_servo_cartesian", ([300.0, 0, 200.0, math.pi, 0, 0],), {"is_radian": True}),
        ("vc_set_cartesian_velocity", ([0.0] * 6,), {"is_radian": True, "duration": 0.1}),
        (
            "set_position",
            (),
            {"x": 300.0, "z": 200.0, "speed": 50.0, "is_radian": True, "wait": True},
        ),
        ("emergency_stop", (), {}),
        ("set_timeout", (1.5,), {}),
        ("register_error_warn_changed_callback", (print,), {}),
        ("release_error_warn_changed_callback", (print,), {}),
    ]
    for name, args, kwargs in calls:
        assert getattr(fake, name)(*args, **kwargs) == getattr(real, name)(*args, **kwargs), name
    for prop in ("connected", "default_is_radian", "mode", "state", "error_code", "warn_code"):
        assert getattr(fake, prop) == getattr(real, prop), prop
    real.disconnect()


def test_every_call_the_driver_makes_fits_the_real_sdk_signature():
    from xarm.wrapper import XArmAPI

    arm, fake, clock = make()
    arm.servo_pose(HOME)
    clock.advance(0.01)
    arm.move_velocity(Twist((0.01, 0.0, 0.0)), 0.1)
    arm.stop()
    arm.move_to(HOME, 0.05)
    arm.stop()
    arm.read_status()
    fake.inject_error(31)
    arm.clear_fault()
    arm.emergency_stop()
    arm.disconnect()
    names = {c.name for c in fake.calls}
    assert len(names) >= 18
    for call in fake.calls:
        signature = inspect.signature(getattr(XArmAPI, call.name))
        signature.bind(None, *call.args, **call.kwargs)  # raises TypeError on a mismatch


def test_connecting_to_a_closed_loopback_port_raises_not_connected():
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        if probe.connect_ex(("127.0.0.1", 502)) == 0:
            pytest.skip("something listens on 127.0.0.1:502")
    arm = XArm6.from_config(dataclasses.replace(CONFIG, ip="127.0.0.1"))
    with pytest.raises(DeviceNotConnectedError, match="connect socket failed"):
        arm.connect()
    assert not arm.is_connected


def test_a_controller_that_accepts_and_never_answers_fails_connect_in_time(silent_controller):
    """Without a deadline the SDK's connect waits about four minutes here (100 version
    requests of 2 s each)."""
    config = dataclasses.replace(CONFIG, ip=silent_controller.ip, connect_timeout_s=0.5)
    arm = XArm6.from_config(config)
    started = time.monotonic()
    with pytest.raises(DeviceTimeoutError) as raised:
        arm.connect()
    elapsed_s = time.monotonic() - started
    assert 0.5 <= elapsed_s < 0.5 + 2.0  # the deadline, plus a margin for a loaded machine
    assert silent_controller.accepted.is_set() and not arm.is_connected
    message = str(raised.value)
    assert f"controller at {silent_controller.ip} (TCP port 502) accepted the connection" in message
    assert "did not answer within 0.5 s (key 'connect_timeout_s')" in message
    arm.disconnect()  # idempotent after a failed connect


class HangingConnect(FakeXArmAPI):
    """``connect`` blocks until ``release`` is set, as the SDK's does on a silent host."""

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.release = threading.Event()

    def connect(self, *args, **kwargs) -> None:
        self.release.wait(10.0)
        super().connect(*args, **kwargs)


def test_a_retry_waits_for_the_abandoned_attempt_and_never_shares_the_sdk_object():
    fake = HangingConnect(CONFIG.ip, is_radian=True, do_not_open=True)
    arm = XArm6(dataclasses.replace(CONFIG, connect_timeout_s=0.5), fake)
    with pytest.raises(DeviceTimeoutError, match="did not answer within 0.5 s"):
        arm.connect()
    with pytest.raises(DeviceTimeoutError, match="previous, abandoned connection attempt"):
        arm.connect()  # the first attempt still hangs: no second one on the same object
    assert len(fake.named("connect")) == 0
    fake.release.set()  # the abandoned attempt connects late and disconnects by itself
    arm.connect()
    assert arm.is_connected and arm.read_status().state is ArmState.READY
    arm.disconnect()


def test_controller_mode_and_state_codes_become_enums():
    arm, fake, _ = make()
    assert (arm.read_status().mode, arm.read_status().state) == (ArmMode.POSITION, ArmState.READY)
    modes = {1: ArmMode.SERVO, 2: ArmMode.MANUAL, 3: ArmMode.MANUAL, 4: ArmMode.OTHER,
             5: ArmMode.VELOCITY, 7: ArmMode.OTHER}  # fmt: skip
    for mode, expected in modes.items():
        fake._mode = mode
        assert arm.read_status().mode is expected
    states = {1: ArmState.MOVING, 2: ArmState.READY, 3: ArmState.PAUSED, 4: ArmState.STOPPED,
              6: ArmState.UNKNOWN}  # fmt: skip
    for state, expected in states.items():
        fake._state = state
        assert arm.read_status().state is expected


SWALLOWING_SDK = textwrap.dedent(
    """
    import time

    from drivers.arm import XArm6
    from drivers.registry import load_device_config
    from tests.drivers.fake_xarm_api import FakeXArmAPI


    class SwallowingApi(FakeXArmAPI):
        def get_position(self, is_radian=None):
            print("waiting", flush=True)
            while True:  # as the SDK's reply wait: a bare except eats KeyboardInterrupt
                try:
                    time.sleep(0.01)
                except BaseException:
                    pass


    config = load_device_config("configs/robot/xarm6.yaml", backend="real").config
    arm = XArm6(config, SwallowingApi(config.ip, is_radian=True, do_not_open=True))
    arm.connect()
    try:
        arm.read_status()
    except KeyboardInterrupt:
        print("interrupted", flush=True)
    """
)


def test_ctrl_c_interrupts_an_sdk_call_even_though_the_sdk_swallows_it():
    process = subprocess.Popen(
        [sys.executable, "-c", SWALLOWING_SDK],
        cwd=CONFIG_ROOT.parent,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert process.stdout.readline() == "waiting\n"
        process.send_signal(signal.SIGINT)
        out, err = process.communicate(timeout=5.0)
    finally:
        process.kill()
    assert (process.returncode, out, err) == (0, "interrupted\n", "")


# --------------------------------------------------------------------- configuration


def test_the_example_config_file_is_valid():
    config = load_device_config(CONFIG_FILE, backend="real").config
    assert type(config) is XArm6Config
    assert 50 <= config.servo_rate_hz <= 200 and config.envelope.max_tilt_rad > 0


@pytest.mark.parametrize(
    ("change", "key"),
    [
        ({"ip": "xarm.local"}, "ip"),
        ({"servo_rate_hz": 500}, "servo_rate_hz"),
        ({"servo_rate_hz": 10}, "servo_rate_hz"),
        ({"velocity_timeout_s": 0.0}, "velocity_timeout_s"),
        ({"tcp": "none"}, "tcp"),
        ({"name": ""}, "name"),
    ],
)
def test_config_validation_names_the_key(change, key):
    with pytest.raises(ValueError, match=f"key '{key}'"):
        dataclasses.replace(CONFIG, **change)


@pytest.mark.parametrize(
    ("change", "key"),
    [
        ({"load_mass_kg": 8.0}, "load_mass_kg"),
        ({"offset_z_m": 2.0}, "offset_z_m"),
        ({"offset_yaw_rad": 4.0}, "offset_yaw_rad"),
    ],
)
def test_tcp_validation_names_the_key(change, key):
    with pytest.raises(ValueError, match=f"key '{key}'"):
        dataclasses.replace(TCP, **change)


def test_registry_builds_the_real_driver_from_the_example_yaml():
    fake = FakeXArmAPI("192.168.1.185", is_radian=True, do_not_open=True)
    with load_device(CONFIG_FILE, backend="real", kind="arm", api=fake) as arm:
        assert isinstance(arm, XArm6) and arm.is_connected
        state = arm.read_status()
    assert not fake.connected
    assert len(state.tcp.xyz_m) == 3 and state.error_code == 0
