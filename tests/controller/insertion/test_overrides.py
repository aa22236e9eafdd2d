"""TELEOP and ESTOP: takeover at once, hand-back to a phase consistent with the contact state,
the e-stop latch and its acknowledgement."""

from dataclasses import replace

import numpy as np
import pytest

from controller.insertion.interface import Phase, TeleopInput
from controller.insertion.machine_config import MachineConfig, Timeouts
from controller.insertion.phases.grasp import GraspStage
from core.devices import Twist
from tests.controller.insertion.world import ToyWorld, make_machine, path

OPERATOR = TeleopInput(connected=True, in_control=True, twist=Twist((0.0, 0.0, 0.01)))
STILL = Twist()


def take_over(world, machine, twist=STILL):
    world.teleop = replace(OPERATOR, twist=twist)
    return world.step(machine)


def hand_back(world, machine):
    world.teleop = TeleopInput(connected=True, hand_back=True)
    world.step(machine)
    world.teleop = TeleopInput(connected=True)
    return machine.transitions[-1]


def test_takeover_is_immediate_and_passes_the_operator_twist_bounded():
    world = ToyWorld()
    machine = make_machine(world)
    world.run_until(machine, Phase.SEARCH)
    command = take_over(world, machine, Twist((1.0, 0.0, 0.0), (0.0, 0.0, 0.3)))
    assert path(machine)[-1] == ("SEARCH", "TELEOP", "operator_takeover")
    limits = MachineConfig().limits
    assert command.twist.linear_m_s == pytest.approx((limits.max_command_speed_m_s, 0.0, 0.0))
    assert command.twist.angular_rad_s == pytest.approx((0.0, 0.0, 0.3))


def test_gripper_buttons_are_honoured_under_teleop():
    world = ToyWorld()
    machine = make_machine(world)
    world.run_until(machine, Phase.APPROACH)
    take_over(world, machine)
    world.teleop = replace(OPERATOR, gripper_open=True)
    opened = world.step(machine).gripper
    world.teleop = replace(OPERATOR, gripper_close=True)
    closed = world.step(machine).gripper
    cfg = MachineConfig().gripper
    assert opened.width_m == cfg.open_width_m
    assert (closed.width_m, closed.force_n) == (cfg.close_width_m, cfg.close_force_n)


def test_hand_back_in_contact_resumes_search_and_finishes():
    world = ToyWorld()
    machine = make_machine(world)
    world.run_until(machine, Phase.SEARCH)
    take_over(world, machine)  # zero operator twist: still pressing on the board
    for _ in range(20):
        take_over(world, machine)
    assert hand_back(world, machine).target is Phase.SEARCH
    assert world.run_until(machine, Phase.DONE) is Phase.DONE


def test_hand_back_without_contact_resumes_approach():
    world = ToyWorld()
    machine = make_machine(world)
    world.run_until(machine, Phase.SEARCH)
    for _ in range(60):  # lift the plug off the board
        take_over(world, machine, Twist((0.0, 0.0, 0.02)))
    assert hand_back(world, machine).target is Phase.APPROACH
    assert world.run_until(machine, Phase.DONE) is Phase.DONE


def test_hand_back_without_a_grasp_resumes_grasp():
    world = ToyWorld()
    machine = make_machine(world)
    world.run_until(machine, Phase.APPROACH)
    world.teleop = replace(OPERATOR, gripper_open=True)
    world.step(machine)
    for _ in range(20):
        take_over(world, machine)
    assert hand_back(world, machine).target is Phase.GRASP
    assert world.run_until(machine, Phase.DONE) is Phase.DONE
    assert world.rezero_count == 2


def test_hand_back_while_holding_before_the_baseline_keeps_the_grasp_and_rezeroes():
    world = ToyWorld()
    machine = make_machine(world)
    world.step(machine)
    while machine.stage is not GraspStage.ZERO:  # settled on the plug, zeroing, no baseline yet
        world.step(machine)
    take_over(world, machine)
    assert hand_back(world, machine).target is Phase.GRASP
    first, rezeroes = len(world.commands), world.rezero_count
    world.run_until(machine, Phase.APPROACH)
    resumed = world.commands[first:]
    # no open-gel capture on the plug held, and the fingers never let go of it
    assert not any(c.capture_open_tactile for c in resumed)
    assert all(c.gripper is None for c in resumed) and world.gripper_holding
    assert world.rezero_count == rezeroes + 1
    assert world.run_until(machine, Phase.DONE) is Phase.DONE


def test_hand_back_with_the_tip_in_the_opening_resumes_align():
    world = ToyWorld()
    machine = make_machine(world)
    world.run_until(machine, Phase.INSERT)
    take_over(world, machine)
    assert hand_back(world, machine).target is Phase.ALIGN
    assert world.run_until(machine, Phase.DONE) is Phase.DONE


def test_hand_back_after_release_resumes_retract():
    world = ToyWorld()
    machine = make_machine(world)
    world.run_until(machine, Phase.RETRACT)
    take_over(world, machine)
    assert hand_back(world, machine).target is Phase.RETRACT
    assert world.run_until(machine, Phase.DONE) is Phase.DONE


def test_time_under_teleop_does_not_count_toward_the_timeouts():
    world = ToyWorld()
    cfg = replace(MachineConfig(), timeouts=replace(Timeouts(), total_s=20.0))  # run: 12.8 s
    machine = make_machine(world, cfg)
    world.run_until(machine, Phase.APPROACH)
    for _ in range(1500):  # 15 s under teleop
        take_over(world, machine)
    hand_back(world, machine)
    assert world.run_until(machine, Phase.DONE) is Phase.DONE


def test_estop_latches_until_released_and_acknowledged():
    world = ToyWorld()
    machine = make_machine(world)
    world.run_until(machine, Phase.INSERT)
    world.teleop = TeleopInput(connected=True, estop=True)
    command = world.step(machine)
    assert path(machine)[-1] == ("INSERT", "ESTOP", "estop")
    assert command.twist == Twist() and command.gripper is None
    world.teleop = TeleopInput(connected=True, estop=True, estop_ack=True)  # ack while held
    for _ in range(5):
        assert world.step(machine).twist == Twist()
    world.teleop = TeleopInput(connected=True)  # released, not acknowledged
    for _ in range(5):
        assert world.step(machine).twist == Twist()
    world.teleop = TeleopInput(connected=True, in_control=True, twist=Twist((0.0, 0.0, 0.01)))
    assert world.step(machine).twist == Twist()  # the operator cannot move it either
    assert machine.phase is Phase.ESTOP
    world.teleop = TeleopInput(connected=True, estop_ack=True)
    world.step(machine)
    assert path(machine)[-1] == ("ESTOP", "ALIGN", "estop_acknowledged")
    world.teleop = TeleopInput(connected=True)
    assert world.run_until(machine, Phase.DONE) is Phase.DONE


def test_estop_from_teleop_and_back_to_the_operator():
    world = ToyWorld()
    machine = make_machine(world)
    world.run_until(machine, Phase.APPROACH)
    take_over(world, machine)
    world.teleop = replace(OPERATOR, estop=True)
    world.step(machine)
    assert path(machine)[-1] == ("TELEOP", "ESTOP", "estop")
    world.teleop = replace(OPERATOR, estop_ack=True)
    command = world.step(machine)
    assert path(machine)[-1] == ("ESTOP", "TELEOP", "estop_acknowledged")
    assert command.twist == Twist()
    assert np.allclose(world.step(machine).twist.linear_m_s, OPERATOR.twist.linear_m_s)


def test_estop_during_grasp_resumes_grasp():
    world = ToyWorld()
    machine = make_machine(world)
    world.step(machine)
    world.teleop = TeleopInput(estop=True)
    world.step(machine)
    world.teleop = TeleopInput(estop_ack=True)
    world.step(machine)
    world.teleop = TeleopInput()
    assert [t.target for t in machine.transitions] == [Phase.ESTOP, Phase.GRASP]
    assert world.run_until(machine, Phase.DONE) is Phase.DONE


@pytest.mark.parametrize("override", ["teleop", "estop"])
def test_a_device_fault_under_an_override_fails(override):
    world = ToyWorld()
    machine = make_machine(world)
    world.run_until(machine, Phase.APPROACH)
    world.teleop = OPERATOR if override == "teleop" else TeleopInput(estop=True)
    world.step(machine)
    world.fault = "gamepad lost"
    world.step(machine)
    assert path(machine)[-1] == (override.upper(), "FAILED", "device_fault")
