"""The teleop demo's machine on the toy world: grasp, then the operator; e-stop latching,
hand-back ending the demo, the view's re-zero, a fault, and its checked table."""

from __future__ import annotations

from controller.insertion.definition import check_definition
from controller.insertion.interface import Phase, TeleopInput
from controller.insertion.teleop_only import TELEOP_ONLY, TeleopOnlyMachine
from core.devices import Twist
from tests.controller.insertion.world import ToyWorld, toy_config

DRIVE = TeleopInput(connected=True, in_control=True, deadman=True,
                    twist=Twist((0.0, 0.01, 0.0), (0.0, 0.0, 0.0)))  # fmt: skip


def grasped() -> tuple[ToyWorld, TeleopOnlyMachine]:
    world = ToyWorld(board=False)
    machine = TeleopOnlyMachine(toy_config(), world.plug, world.hole)
    assert world.run_until(machine, Phase.TELEOP, max_s=10.0) is Phase.TELEOP
    return world, machine


def path(machine):
    return [(t.source.name, t.target.name, t.reason) for t in machine.transitions]


def test_the_table_is_checked_and_every_phase_reachable():
    check_definition(TELEOP_ONLY)


def test_grasp_then_the_operator_drives_and_the_pad_is_ignored_during_the_grasp():
    world = ToyWorld(board=False, teleop=DRIVE)  # a deflected stick from the start
    machine = TeleopOnlyMachine(toy_config(), world.plug, world.hole)
    y0 = world.p[1]
    world.run_until(machine, Phase.TELEOP, max_s=10.0)
    assert abs(world.p[1] - y0) < 1e-9  # no motion before the grasp was zeroed
    assert world.rezero_count == 1 and path(machine) == [("GRASP", "TELEOP", "grasped_and_zeroed")]
    command = world.step(machine)
    assert command.twist.linear_m_s == (0.0, 0.01, 0.0)
    assert machine.in_hand_estimates == ()  # the operator inserts: nothing felt


def test_estop_latches_until_released_and_acknowledged():
    world, machine = grasped()
    world.teleop = TeleopInput(connected=True, estop=True)
    world.step(machine)
    assert machine.phase is Phase.ESTOP
    world.teleop = TeleopInput(connected=True, estop=True, estop_ack=True)  # held: ignored
    world.step(machine)
    world.teleop = DRIVE  # released, the stick deflected, no acknowledgement
    for _ in range(5):
        assert world.step(machine).twist.linear_m_s == (0.0, 0.0, 0.0)
    assert machine.phase is Phase.ESTOP
    world.teleop = TeleopInput(connected=True, estop_ack=True)
    world.step(machine)
    assert machine.phase is Phase.TELEOP
    assert path(machine)[-2:] == [("TELEOP", "ESTOP", "estop"),
                                  ("ESTOP", "TELEOP", "estop_acknowledged")]  # fmt: skip


def test_hand_back_ends_the_demo_and_rezero_is_one_still_tick():
    world, machine = grasped()
    machine.request_rezero()
    world.teleop = DRIVE
    command = world.step(machine)
    assert command.rezero_tactile and command.twist.linear_m_s == (0.0, 0.0, 0.0)
    assert world.step(machine).twist.linear_m_s == (0.0, 0.01, 0.0)  # once only
    world.teleop = TeleopInput(connected=True, hand_back=True)
    world.step(machine)
    assert machine.phase is Phase.DONE and path(machine)[-1] == ("TELEOP", "DONE", "hand_back")


def test_a_device_fault_fails_the_demo():
    world, machine = grasped()
    world.fault = "gamepad: lost while in control"
    world.step(machine)
    assert machine.phase is Phase.FAILED and path(machine)[-1][2] == "device_fault"
