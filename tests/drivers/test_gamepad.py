"""The gamepad driver against SDL's virtual game controller, seen by pygame as a real device.

See tests/drivers/virtual_joystick.py for how the device is made and what SDL does with it.
"""

from __future__ import annotations

import ctypes
from pathlib import Path

import pygame
import pytest
from hypothesis import given
from hypothesis import strategies as st
from pygame._sdl2 import controller as sdl_controller

from core.clock import ManualClock
from core.config import ConfigError, build
from core.errors import DeviceNotConnectedError
from drivers.gamepad import AxisBinding, GamepadConfig, axis_value
from drivers.gamepad.mapping import AXIS_NAMES, BUTTON_NAMES
from drivers.gamepad.pad import AXIS_IDS, BUTTON_IDS, PygameGamepad
from drivers.registry import load_device, load_device_config
from tests.drivers.virtual_joystick import (
    VIRTUAL_AXES,
    VIRTUAL_BUTTONS,
    VirtualJoystick,
    pygame_sdl_or_skip,
)

XBOX_YAML = Path(__file__).resolve().parents[2] / "configs" / "gamepad" / "xbox.yaml"
FULL = 32767


def raw(unit: float) -> int:
    """Controller axis value for a deflection in [-1, 1]."""
    return round(unit * FULL)


@pytest.fixture(scope="module")
def sdl():
    return pygame_sdl_or_skip()


@pytest.fixture
def device(sdl):
    with VirtualJoystick(sdl) as joystick:
        yield joystick
    pygame.event.clear()


@pytest.fixture
def config():
    return load_device_config(XBOX_YAML, backend="real").config


@pytest.fixture
def gamepad(device, config):
    with PygameGamepad(config) as pad:
        yield pad


def test_virtual_device_is_a_game_controller_with_sdl_automatic_mapping(device):
    index = next(i for i in range(sdl_controller.get_count()) if sdl_controller.is_controller(i))
    controller = sdl_controller.Controller(index)
    try:
        mapping = controller.get_mapping()
    finally:
        controller.quit()
    for i, name in enumerate(VIRTUAL_AXES):
        assert mapping[name] == f"a{i}"
    for i, name in enumerate(VIRTUAL_BUTTONS):
        assert mapping[name] == f"b{i}"


def test_background_events_hint_is_seen_by_sdl(sdl):
    sdl.SDL_GetHint.restype = ctypes.c_char_p
    assert sdl.SDL_GetHint(b"SDL_JOYSTICK_ALLOW_BACKGROUND_EVENTS") == b"1"


def test_driver_tables_cover_every_sdl_name():
    assert set(AXIS_IDS) == set(AXIS_NAMES)
    assert set(BUTTON_IDS) == set(BUTTON_NAMES)


def test_axes_and_buttons_map_to_actions(device, gamepad):
    device.set_axis("lefty", -32768)  # left stick fully up
    device.set_axis("leftx", FULL)  # left stick fully right
    device.set_axis("rightx", FULL)  # right stick fully right; wz has scale 0.5
    device.set_button("leftshoulder", True)
    device.set_button("start", True)
    state = gamepad.read()
    assert state.connected
    assert state.axes == {"vx": 1.0, "vy": -1.0, "vz": 0.0, "wz": -0.5}
    assert state.buttons == {
        "deadman": True, "estop": False, "hand_back": True,
        "estop_ack": False, "gripper_open": False, "gripper_close": False,
    }  # fmt: skip

    device.set_button("leftshoulder", False)
    device.set_button("b", True)
    state = gamepad.read()
    assert {k: state.buttons[k] for k in ("deadman", "estop", "hand_back")} == {
        "deadman": False, "estop": True, "hand_back": True,
    }  # fmt: skip


def test_dead_zone_through_the_device(device, gamepad, config):
    dz = config.dead_zone
    device.set_axis("righty", raw(-0.9 * dz))  # inside, up
    assert gamepad.read().axes["vz"] == 0.0
    device.set_axis("righty", raw(-dz))  # at the edge
    assert gamepad.read().axes["vz"] == 0.0
    device.set_axis("righty", raw(-dz) - 33)  # just past the edge: small, not a jump
    assert 0.0 < gamepad.read().axes["vz"] < 0.002
    device.set_axis("righty", raw(-0.5))
    assert gamepad.read().axes["vz"] == pytest.approx((0.5 - dz) / (1 - dz), abs=1e-4)


def test_trigger_axis_reads_zero_released_one_pressed(device, sdl):
    cfg = GamepadConfig(
        axes={"close": AxisBinding(axis="righttrigger")},
        buttons={"deadman": "a", "estop": "b", "hand_back": "y"},
        dead_zone=0.1,
    )
    with PygameGamepad(cfg) as pad:
        assert pad.read().axes["close"] == 0.0
        device.set_axis("righttrigger", FULL)
        assert pad.read().axes["close"] == 1.0
        device.set_axis("righttrigger", raw(0.55))
        assert pad.read().axes["close"] == pytest.approx(0.5, abs=1e-4)


def test_unplug_gives_a_safe_state_without_raising(device, gamepad):
    device.set_axis("lefty", -32768)
    device.set_button("leftshoulder", True)
    assert gamepad.read().axes["vx"] == 1.0

    device.detach()
    for _ in range(2):
        state = gamepad.read()
        assert not state.connected
        assert state.axes == {"vx": 0.0, "vy": 0.0, "vz": 0.0, "wz": 0.0}
        assert set(state.buttons) >= {"deadman", "estop", "hand_back"}
        assert not any(state.buttons.values())
    assert gamepad.is_connected  # the driver stays open, waiting for the pad


def test_replug_reopens_the_controller(device, gamepad, sdl):
    device.detach()
    assert not gamepad.read().connected
    with VirtualJoystick(sdl) as again:
        again.set_axis("leftx", -32768)  # left stick fully left
        again.set_button("b", True)
        state = gamepad.read()
        assert state.connected
        assert state.axes["vy"] == 1.0
        assert state.buttons["estop"]
    assert not gamepad.read().connected


def test_plug_and_unplug_between_two_reads_does_not_raise(device, gamepad, sdl):
    bouncing = VirtualJoystick(sdl)  # a connector bouncing faster than the read rate
    bouncing.attach()
    bouncing.detach()
    assert gamepad.read().connected
    device.detach()
    bouncing.attach()
    bouncing.detach()
    assert not gamepad.read().connected


def test_connect_without_a_pad_names_what_to_check(sdl, config):
    pad = PygameGamepad(config)
    with pytest.raises(DeviceNotConnectedError) as err:
        pad.connect()
    assert err.value.device == "gamepad"
    assert "no game controller attached" in str(err.value)
    assert "USB cable" in str(err.value)
    assert not pad.is_connected


def test_connect_with_an_unmapped_joystick_points_to_the_mapping(sdl, config):
    with VirtualJoystick(sdl, game_controller=False):
        with pytest.raises(DeviceNotConnectedError, match="SDL_GAMECONTROLLERCONFIG"):
            PygameGamepad(config).connect()
    pygame.event.clear()


def test_lifecycle(device, config):
    pad = PygameGamepad(config)
    with pytest.raises(DeviceNotConnectedError, match="before connect"):
        pad.read()
    with pytest.raises(RuntimeError, match="boom"):
        with pad:
            assert pad.is_connected and pad.read().connected
            raise RuntimeError("boom")
    assert not pad.is_connected
    pad.disconnect()  # idempotent
    with pytest.raises(DeviceNotConnectedError):
        pad.read()


@pytest.mark.parametrize(
    ("invert", "scale", "expected"),
    [(False, 1.0, 1.0), (True, 1.0, -1.0), (False, 0.25, 0.25), (True, 0.5, -0.5)],
)
def test_invert_and_scale(invert, scale, expected):
    binding = AxisBinding(axis="leftx", invert=invert, scale=scale)
    assert axis_value(FULL, binding, 0.1) == expected
    assert axis_value(-32768, binding, 0.1) == -expected


@given(
    dz=st.floats(0.0, 0.5),
    u=st.floats(-1.0, 1.0),
    scale=st.floats(0.01, 1.0),
    invert=st.booleans(),
)
def test_axis_value_is_bounded_odd_and_zero_in_the_dead_zone(dz, u, scale, invert):
    binding = AxisBinding(axis="lefty", invert=invert, scale=scale)
    value = axis_value(round(u * FULL), binding, dz)
    assert abs(value) <= scale
    if abs(round(u * FULL)) <= dz * FULL:
        assert value == 0.0
    assert axis_value(-round(u * FULL), binding, dz) == -value


@given(dz=st.floats(0.0, 0.5), step=st.integers(1, 50))
def test_axis_value_is_continuous_at_the_dead_zone_edge(dz, step):
    binding = AxisBinding(axis="lefty")
    edge = int(dz * FULL)
    # Just past the edge the output is within a few counts' worth of zero.
    assert 0.0 <= axis_value(edge + step, binding, dz) <= (step + 1) / (FULL * (1 - dz))


def test_xbox_yaml_binds_the_safety_buttons(config):
    assert dict(config.buttons) == {
        "deadman": "leftshoulder", "estop": "b", "hand_back": "start",
        "estop_ack": "back", "gripper_open": "y", "gripper_close": "a",
    }  # fmt: skip
    assert config.axes["vx"] == AxisBinding(axis="lefty", invert=True, scale=1.0)


GOOD = {
    "name": "pad",
    "dead_zone": 0.1,
    "axes": {"vx": {"axis": "lefty", "invert": True, "scale": 1.0}},
    "buttons": {"deadman": "leftshoulder", "estop": "b", "hand_back": "y"},
}


def axes(**entry):
    return {"axes": {"vx": {"axis": "lefty", "invert": False, "scale": 1.0, **entry}}}


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"dead_zone": 0.6}, "key 'dead_zone': expected a number in [0.0, 0.5]"),
        (axes(axis="z"), "key 'axes.vx.axis'"),
        (axes(scale=0), "key 'axes.vx.scale': expected a number in (0, 1]"),
        (axes(scale=2), "key 'axes.vx.scale'"),
        (axes(invert="yes"), "key 'axes.vx.invert'"),
        (axes(gain=1), "unknown key 'axes.vx.gain'"),
        ({"axes": {"vx": {"invert": True, "scale": 1.0}}}, "missing key 'axes.vx.axis'"),
        (
            {"axes": {"vx": axes()["axes"]["vx"], "vz": axes()["axes"]["vx"]}},
            "actions 'vx' and 'vz' both use 'lefty'",
        ),
        ({"buttons": {"deadman": "l1", "estop": "b", "hand_back": "y"}}, "key 'buttons.deadman'"),
        ({"buttons": {"estop": "b", "hand_back": "y"}}, "missing required action(s) deadman"),
        (
            {"buttons": {"deadman": "b", "estop": "b", "hand_back": "y"}},
            "actions 'deadman' and 'estop' both use 'b'",
        ),
        ({"rate_hz": 100}, "unknown key 'rate_hz'"),
    ],
)
def test_config_validation_errors(change, message):
    with pytest.raises(ConfigError) as err:
        build(GamepadConfig, {**GOOD, **change}, source="pad.yaml")
    assert str(err.value).startswith("pad.yaml: ")
    assert message in str(err.value)


def test_readings_are_stamped_on_the_injected_clock(device, config):
    clock = ManualClock(3.5)
    with PygameGamepad(config, clock) as pad:
        assert pad.read().t_s == 3.5
        clock.advance(0.25)
        assert pad.read().t_s == 3.75


def test_registry_builds_the_real_driver_for_the_virtual_device(device, config):
    with load_device(XBOX_YAML, backend="real", kind="gamepad") as pad:
        assert isinstance(pad, PygameGamepad) and pad.config == config
        device.set_button("leftshoulder", True)
        device.set_axis("leftx", FULL)
        state = pad.read()
    assert state.connected and state.buttons["deadman"] and state.axes["vy"] == -1.0
