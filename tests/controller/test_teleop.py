"""Teleop arbitration through the scripted gamepad twin: takeover, scaling, hand-back, the
e-stop and gripper buttons, a lost pad, the deadman."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from controller.teleop import TeleopArbiter, TeleopConfig, lost_in_control
from core.clock import ManualClock
from core.config import CONFIG_ROOT as CONFIGS
from core.devices import GamepadState
from drivers import registry
from drivers.sim.twins.gamepad import PadEvent

CONFIG = TeleopConfig(stick_speed_m_s=0.02, stick_angular_speed_rad_s=0.2)
TICK = 0.01


@pytest.fixture
def clock():
    return ManualClock()


@pytest.fixture
def pad(clock):
    device = registry.load_device(CONFIGS / "gamepad" / "xbox.yaml", backend="sim", clock=clock)
    with device:
        yield device


def run(pad, clock, events, seconds, config=CONFIG, deadman=True):
    """Arbitrate the script for ``seconds`` at 100 Hz, the deadman held from the start unless
    ``deadman`` is False; the TeleopInput of every tick. Events are played half a tick early,
    so the clock's round-off cannot move them a tick later."""
    held = [PadEvent(0.0, buttons={"deadman": True})] if deadman else []
    pad.play(held + [dataclasses.replace(e, t_s=max(0.0, e.t_s - TICK / 2)) for e in events])
    arbiter = TeleopArbiter(config)
    out = []
    for _ in range(round(seconds / TICK)):
        out.append(arbiter.update(pad.read()))
        clock.advance(TICK)
    return out


def at(inputs, t_s):
    return inputs[round(t_s / TICK)]


def test_a_stick_takes_over_at_once_and_scales_to_speed(pad, clock):
    inputs = run(pad, clock, [PadEvent(0.1, axes={"vx": 0.5, "wz": -0.5})], 0.2)
    assert not at(inputs, 0.09).in_control and at(inputs, 0.09).twist.linear_m_s == (0, 0, 0)
    now = at(inputs, 0.1)
    assert now.in_control and now.connected
    assert now.twist.linear_m_s == pytest.approx((0.01, 0.0, 0.0))
    assert now.twist.angular_rad_s == pytest.approx((0.0, 0.0, -0.1))


def test_a_diagonal_is_no_faster_than_an_axis(pad, clock):
    inputs = run(pad, clock, [PadEvent(0.0, axes={"vx": 1.0, "vy": 1.0, "vz": 1.0})], 0.05)
    assert np.linalg.norm(inputs[-1].twist.linear_m_s) == pytest.approx(0.02)
    assert inputs[-1].twist.linear_m_s[0] == pytest.approx(0.02 / math.sqrt(3))


def test_control_stays_with_the_operator_until_hand_back(pad, clock):
    events = [
        PadEvent(0.1, axes={"vx": 0.5}),
        PadEvent(0.2, axes={"vx": 0.0}),  # sticks released: still in control, holding still
        PadEvent(0.3, buttons={"hand_back": True}),
        PadEvent(0.5, buttons={"hand_back": False}),
    ]
    inputs = run(pad, clock, events, 0.6)
    assert at(inputs, 0.25).in_control and at(inputs, 0.25).twist.linear_m_s == (0, 0, 0)
    assert at(inputs, 0.3).hand_back and not at(inputs, 0.3).in_control
    assert [i.hand_back for i in inputs].count(True) == 1  # an edge, not a level
    assert not at(inputs, 0.55).in_control


def test_a_stick_held_through_hand_back_needs_to_return_to_neutral(pad, clock):
    events = [
        PadEvent(0.1, axes={"vy": 0.8}),
        PadEvent(0.2, buttons={"hand_back": True}),
        PadEvent(0.3, axes={"vy": 0.0}),
        PadEvent(0.4, axes={"vy": -0.3}),
    ]
    inputs = run(pad, clock, events, 0.5)
    assert not at(inputs, 0.25).in_control  # still deflected, but handed back
    assert at(inputs, 0.25).twist.linear_m_s == (0, 0, 0)
    assert at(inputs, 0.4).in_control  # a fresh deflection takes over again
    assert at(inputs, 0.4).twist.linear_m_s[1] == pytest.approx(-0.3 * 0.02)


def test_estop_is_held_and_acknowledge_and_gripper_are_edges(pad, clock):
    events = [
        PadEvent(0.1, buttons={"estop": True}),
        PadEvent(0.2, buttons={"estop": False, "estop_ack": True}),
        PadEvent(0.3, buttons={"gripper_close": True}),
        PadEvent(0.4, buttons={"gripper_close": False, "gripper_open": True}),
    ]
    inputs = run(pad, clock, events, 0.5)
    assert [i.estop for i in inputs].count(True) == 10
    assert [i.estop_ack for i in inputs].count(True) == 1 and at(inputs, 0.2).estop_ack
    assert [i.gripper_close for i in inputs].count(True) == 1 and at(inputs, 0.3).gripper_close
    assert [i.gripper_open for i in inputs].count(True) == 1 and at(inputs, 0.4).gripper_open
    assert not any(i.in_control for i in inputs)  # buttons do not take over


def test_a_lost_pad_in_control_is_reported(pad, clock):
    events = [PadEvent(0.1, axes={"vz": 0.5}), PadEvent(0.2, attached=False)]
    inputs = run(pad, clock, events, 0.3)
    lost = at(inputs, 0.2)
    assert not lost.connected and lost.in_control and lost.twist.linear_m_s == (0, 0, 0)
    assert lost_in_control(lost) and not lost_in_control(at(inputs, 0.15))


def test_a_lost_pad_not_in_control_is_not_a_trip(pad, clock):
    inputs = run(pad, clock, [PadEvent(0.1, attached=False)], 0.2)
    assert not any(lost_in_control(i) for i in inputs)


def test_the_deadman_is_always_required(pad, clock):
    events = [
        PadEvent(0.1, axes={"vx": 1.0}),
        PadEvent(0.2, buttons={"deadman": True}),
        PadEvent(0.3, buttons={"deadman": False}),
    ]
    inputs = run(pad, clock, events, 0.4, deadman=False)
    assert not at(inputs, 0.15).in_control and at(inputs, 0.15).twist.linear_m_s == (0, 0, 0)
    assert at(inputs, 0.25).in_control and at(inputs, 0.25).twist.linear_m_s[0] == 0.02
    assert at(inputs, 0.35).in_control and at(inputs, 0.35).twist.linear_m_s[0] == 0.0


def test_the_takeover_threshold():
    arbiter = TeleopArbiter(TeleopConfig(takeover_threshold=0.2))
    held = {"deadman": True}
    assert not arbiter.update(GamepadState(0.0, True, {"vx": 0.1}, held)).in_control
    assert arbiter.update(GamepadState(0.0, True, {"vx": 0.3}, held)).in_control


def test_no_pad_configured():
    assert TeleopArbiter(CONFIG).update(None) == TeleopArbiter(CONFIG).update(None)
    assert not TeleopArbiter(CONFIG).update(None).in_control
