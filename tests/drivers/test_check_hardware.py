"""tactile check-hardware (drivers/check_hardware.py) as a user runs it: one line per
device, exit 0/1/2."""

from __future__ import annotations

import os
import pty
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml

from drivers import check_hardware
from tests.script_runs import exit_code

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "scripts" / "check_hardware.py"
CONFIGS = ROOT / "configs"
SIM_CONFIGS = [
    CONFIGS / "robot" / "xarm6.yaml",
    CONFIGS / "gripper" / "hande.yaml",
    CONFIGS / "sensors" / "gelsight_mini_camera.yaml",
    CONFIGS / "sensors" / "digit_camera.yaml",
    CONFIGS / "gamepad" / "xbox.yaml",
    CONFIGS / "force_torque" / "jig.yaml",
]


def variant(tmp_path: Path, source: Path, name: str, **changes) -> str:
    """A copy of ``source`` with top-level keys changed (a dotted key changes a sub-key)."""
    data = yaml.safe_load(source.read_text())
    for key, value in changes.items():
        *parents, leaf = key.split("__")
        target = data
        for parent in parents:
            target = target[parent]
        target[leaf] = value
    path = tmp_path / name
    path.write_text(yaml.safe_dump(data))
    return str(path)


def test_the_sim_configs_all_report_ok_from_the_command_line(capsys):
    code = exit_code("check_hardware", list(map(str, SIM_CONFIGS)))
    captured = capsys.readouterr()
    assert code == 0, captured.out + captured.err
    lines = captured.out.splitlines()
    assert len(lines) == len(SIM_CONFIGS)
    for line, path in zip(lines, SIM_CONFIGS, strict=True):
        assert line.startswith("OK ") and str(path.relative_to(ROOT)) in line
    assert "TCP at (0.350, 0.000, 0.200) m" in lines[0]
    assert "320x240 frame" in lines[2] and "240x320 frame" in lines[3]
    assert captured.err == ""


def test_default_configs_are_the_robot_set(capsys):
    assert check_hardware.main([]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [line.split()[1] for line in lines] == ["arm", "gripper", "tactile", "gamepad"]


@pytest.mark.parametrize(
    ("source", "change", "message"),
    [
        ("robot/xarm6.yaml", {"servo_rate_hz": 500}, "key 'servo_rate_hz': expected a number"),
        ("robot/xarm6.yaml", {"sim__max_accel_m_s2": -1}, "key 'sim.max_accel_m_s2'"),
        ("robot/xarm6.yaml", {"sim__start_z_m": 0.9}, "key 'sim.start_z_m'"),
        ("gripper/hande.yaml", {"slave_id": 300}, "key 'slave_id'"),
        ("gamepad/xbox.yaml", {"buttons__deadman": "l1"}, "key 'buttons.deadman'"),
        ("gamepad/xbox.yaml", {"type": "joystick"}, "unknown device type 'joystick'; known:"),
        ("sensors/digit_camera.yaml", {"backend": "fake"}, "key 'backend': expected one of"),
    ],
)
def test_a_bad_config_exits_2_with_one_line_naming_file_and_key(
    tmp_path, capsys, source, change, message
):
    bad = variant(tmp_path, CONFIGS / source, "bad.yaml", **change)
    good = str(CONFIGS / "force_torque" / "jig.yaml")
    assert check_hardware.main([good, bad]) == 2
    out, err = capsys.readouterr()
    assert out == ""  # nothing was probed
    assert len(err.splitlines()) == 1
    assert err.startswith(f"check_hardware: error: {bad}: ") and message in err


@pytest.mark.parametrize("argv", [["--backend", "fake"], ["--verbose"], ["missing.yaml"]])
def test_bad_arguments_exit_2_with_one_line(capsys, argv):
    with pytest.raises(SystemExit) as exit_info:
        code = check_hardware.main(argv)
        raise SystemExit(code)
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1 and err.startswith("check_hardware: error: ")


def test_a_tool_port_gripper_needs_the_arm(tmp_path, capsys):
    gripper = variant(tmp_path, CONFIGS / "gripper" / "hande.yaml", "g.yaml", transport="xarm_tool")
    assert check_hardware.main([gripper, "--backend", "real"]) == 2
    assert "key 'transport': 'xarm_tool' reaches the gripper through the arm" in (
        capsys.readouterr().err
    )


def test_absent_real_devices_fail_with_the_drivers_message_and_exit_1(tmp_path, capsys):
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        if probe.connect_ex(("127.0.0.1", 502)) == 0:
            pytest.skip("something listens on 127.0.0.1:502")
    paths = [
        variant(tmp_path, CONFIGS / "robot" / "xarm6.yaml", "arm.yaml", ip="127.0.0.1"),
        variant(
            tmp_path, CONFIGS / "gripper" / "hande.yaml", "g.yaml", port=str(tmp_path / "ttyX")
        ),
        variant(
            tmp_path,
            CONFIGS / "sensors" / "gelsight_mini_camera.yaml",
            "cam.yaml",
            by_id_dir=str(tmp_path / "by-id"),
        ),
    ]
    assert check_hardware.main([*paths, "--backend", "real"]) == 1
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) == 3
    assert lines[0].startswith("FAIL arm xarm6/real")
    assert (
        "DeviceNotConnectedError: xarm6: cannot connect to the controller at 127.0.0.1" in lines[0]
    )
    assert "serial port" in lines[1] and "not found" in lines[1] and "adapter" in lines[1]
    assert "by-id does not exist" in lines[2] and "'video'" in lines[2]
    for line in lines:  # one hint a line: the driver's own, or the tool's when it gave none
        assert line.lower().count("check") == 1, line


def test_a_sim_only_type_refuses_the_real_backend(capsys):
    assert (
        check_hardware.main([str(CONFIGS / "force_torque" / "jig.yaml"), "--backend", "real"]) == 2
    )
    assert "has no 'real' driver yet; known: sim" in capsys.readouterr().err


# ------------------------------------------------------------------------------- silence


def run_script(*args: str, timeout_s: float) -> tuple[subprocess.CompletedProcess, float]:
    started = time.monotonic()
    result = subprocess.run(
        [sys.executable, str(SCRIPT), *args],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=timeout_s,
    )
    return result, time.monotonic() - started


def test_a_silent_arm_and_its_tool_port_gripper_fail_within_the_timeout(
    tmp_path, silent_controller, capfd
):
    """The arm accepts TCP and never replies: each device fails in connect_timeout_s (0.5 s
    here) with one line, instead of the SDK's four minutes. Run in this process, so the time
    is the tool's, without an interpreter's start-up."""
    arm = variant(
        tmp_path, CONFIGS / "robot" / "xarm6.yaml", "arm.yaml",
        ip=silent_controller.ip, connect_timeout_s=0.5,
    )  # fmt: skip
    gripper = variant(tmp_path, CONFIGS / "gripper" / "hande.yaml", "g.yaml", transport="xarm_tool")
    started = time.monotonic()
    code = exit_code("check_hardware", [arm, gripper, "--backend", "real"])
    elapsed_s = time.monotonic() - started
    captured = capfd.readouterr()  # at the descriptors: the SDK logs past Python's streams
    assert code == 1, captured.out + captured.err
    assert elapsed_s < 2 * 0.5 + 1.0  # two connects of 0.5 s, plus a margin
    lines = captured.out.splitlines()
    assert len(lines) == 2
    assert lines[0].startswith("FAIL arm xarm6/real")
    assert lines[1].startswith("FAIL gripper hande/real")
    for line in lines:
        assert f"DeviceTimeoutError: xarm6{' (tool port)' if 'gripper' in line else ''}: " in line
        assert "accepted the connection but did not answer within 0.5 s" in line
        assert "key 'ip' is the xArm control box" in line  # the arm driver's hint, both
        assert line.lower().count("check") == 1, line  # given once
    assert captured.err == ""  # neither the SDK's banner nor its log


def test_ctrl_c_during_a_silent_connect_ends_at_once(tmp_path, silent_controller):
    arm = variant(
        tmp_path, CONFIGS / "robot" / "xarm6.yaml", "arm.yaml",
        ip=silent_controller.ip, connect_timeout_s=30.0,
    )  # fmt: skip
    process = subprocess.Popen(
        [sys.executable, str(SCRIPT), arm, "--backend", "real"],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert silent_controller.accepted.wait(20.0), "the script never reached the arm"
        time.sleep(0.3)  # inside the SDK's connect, waiting for a reply
        process.send_signal(signal.SIGINT)
        sent = time.monotonic()
        out, err = process.communicate(timeout=10.0)
        elapsed_s = time.monotonic() - sent
    finally:
        process.kill()
    assert process.returncode == 130
    assert elapsed_s < 3.0  # not the 30 s connect timeout
    assert out == ""
    assert err.splitlines()[-1] == "check_hardware: interrupted" and "Traceback" not in err


def test_a_silent_serial_gripper_fails_in_its_attempts_and_pymodbus_stays_quiet(tmp_path):
    """A pseudo-terminal with nothing behind it: 3 attempts of 0.1 s, then one FAIL line.
    pymodbus logs every timeout itself; none of it may reach the terminal."""
    controller, device = pty.openpty()
    try:
        gripper = variant(
            tmp_path, CONFIGS / "gripper" / "hande.yaml", "g.yaml",
            port=os.ttyname(device), timeout_s=0.1, retries=2,
        )  # fmt: skip
        result, _ = run_script(gripper, "--backend", "real", timeout_s=60)
    finally:
        os.close(controller)
        os.close(device)
    assert result.returncode == 1
    line = result.stdout.strip()
    assert line.startswith("FAIL gripper hande/real") and "\n" not in line
    assert "DeviceTimeoutError" in line and "3 attempt(s) of 0.1 s" in line
    assert result.stderr == ""
