"""The press-spiral machine outside autonomy and at its limits, in the toy world (the blind
baseline's F/T reading): the operator takes over at once and hands back to GRASP's settle
with the plug held (no open gel taken, the pattern's progress kept), the e-stop latches until
acknowledged, a dropped plug is a slip (the gripper no longer holding), and a force or tilt
past the limits stops the run."""

from __future__ import annotations

from dataclasses import replace

import pytest

from controller.insertion.interface import Phase, TeleopInput
from controller.insertion.spiral import SpiralMachine
from controller.insertion.spiral.spiral_grasp import GraspStage
from core.devices import Twist
from tests.controller.insertion.test_blind import SMALL, reasons
from tests.controller.insertion.world import ToyWorld

OPERATOR = TeleopInput(connected=True, in_control=True, twist=Twist((1.0, 0.0, 0.0)))


def until(world: ToyWorld, machine: SpiralMachine, phase: Phase, max_s: float = 60.0) -> None:
    while machine.phase is not phase and world.t_s < max_s:
        world.step(machine)
    assert machine.phase is phase


def finish(world: ToyWorld, machine: SpiralMachine, max_s: float = 120.0) -> None:
    while machine.phase not in (Phase.DONE, Phase.FAILED) and world.t_s < max_s:
        world.step(machine)


def test_an_operator_takes_over_at_once_and_hands_back_to_the_settle_keeping_the_pattern():
    world = ToyWorld()
    machine = SpiralMachine(SMALL, world.plug, world.hole)
    until(world, machine, Phase.SEARCH)
    for _ in range(150):  # into the sweep
        world.step(machine)
    swept_m = machine.memory.s_m
    world.teleop = OPERATOR
    command = world.step(machine)
    assert machine.phase is Phase.TELEOP and command.rule == "teleop.operator"
    assert command.twist.linear_m_s == pytest.approx((SMALL.move_speed_m_s, 0.0, 0.0))
    world.teleop = replace(OPERATOR, twist=Twist())
    world.step(machine)
    world.teleop = TeleopInput(connected=True, hand_back=True)
    before = len(world.commands)
    world.step(machine)
    world.teleop = TeleopInput(connected=True)
    assert machine.transitions[-1].reason == "hand_back"
    assert machine.phase is Phase.GRASP and machine.stage is GraspStage.CLOSE
    finish(world, machine)
    assert not any(c.capture_open_tactile for c in world.commands[before:])
    assert machine.memory.s_m >= swept_m  # the pattern went on from where it was
    assert reasons(machine)[-3:] == ["bottomed", "released", "retracted"]


def test_the_gripper_buttons_are_the_operators():
    world = ToyWorld()
    machine = SpiralMachine(SMALL, world.plug, world.hole)
    until(world, machine, Phase.APPROACH)
    world.teleop = replace(OPERATOR, gripper_open=True)
    assert world.step(machine).gripper == SMALL.gripper.open_target(SMALL.gripper.open_width_m)
    world.teleop = replace(OPERATOR, gripper_close=True)
    assert world.step(machine).gripper == SMALL.gripper.close_target()


def test_the_estop_latches_until_released_and_acknowledged():
    world = ToyWorld()
    machine = SpiralMachine(SMALL, world.plug, world.hole)
    until(world, machine, Phase.APPROACH)
    world.teleop = TeleopInput(connected=True, estop=True)
    for _ in range(20):
        command = world.step(machine)
        assert machine.phase is Phase.ESTOP and command.twist == Twist()
    world.teleop = TeleopInput(connected=True)  # released, not yet acknowledged
    world.step(machine)
    assert machine.phase is Phase.ESTOP
    world.teleop = TeleopInput(connected=True, estop_ack=True)
    world.step(machine)
    assert machine.transitions[-1].reason == "estop_acknowledged"
    assert machine.phase is Phase.GRASP
    world.teleop = TeleopInput(connected=True)
    finish(world, machine)
    assert machine.phase is Phase.DONE


def test_time_under_the_operator_does_not_count_against_the_budget():
    world = ToyWorld()
    machine = SpiralMachine(replace(SMALL, timeout_s=5.0), world.plug, world.hole)
    until(world, machine, Phase.APPROACH)
    world.teleop = replace(OPERATOR, twist=Twist())
    for _ in range(800):  # 8 s held by the operator
        world.step(machine)
    assert machine.phase is Phase.TELEOP


def test_a_plug_dropped_in_the_search_is_a_slip():
    world = ToyWorld()
    machine = SpiralMachine(SMALL, world.plug, world.hole)
    until(world, machine, Phase.SEARCH)
    world.drop_plug = True
    world.step(machine)
    assert machine.phase is Phase.FAILED and reasons(machine)[-1] == "slip"


@pytest.mark.parametrize(("force_n", "tilt_rad", "exceeded"), [
    (SMALL.tared_force_limit_n - 0.1, 0.0, False),
    (SMALL.tared_force_limit_n + 0.1, 0.0, True),
    (0.0, SMALL.tilt_limit_rad + 0.01, True),
])  # fmt: skip
def test_the_tared_force_or_the_tilt_past_its_limit_stops_the_run(force_n, tilt_rad, exceeded):
    world = ToyWorld()
    machine = SpiralMachine(SMALL, world.plug, world.hole)
    until(world, machine, Phase.SEARCH)
    machine.memory.tared, machine.memory.bias_n = True, 0.0
    machine.force_n = force_n
    obs = world.observe()
    rpy = (obs.arm.tcp.rpy_rad[0] + tilt_rad, *obs.arm.tcp.rpy_rad[1:])
    tilted = replace(obs, arm=replace(obs.arm, tcp=replace(obs.arm.tcp, rpy_rad=rpy)))
    assert machine._limit_exceeded(tilted) is exceeded
