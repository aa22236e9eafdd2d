"""FEEL on the toy world (tests/controller/insertion/world.py, whose plug may be turned in the
hand): the tilt found by rocking, the search aimed with it, and a face that never lies flat."""

from dataclasses import replace

import numpy as np
import pytest

from controller.insertion.interface import Phase
from controller.insertion.machine_config import MachineConfig
from controller.insertion.phases.feel import FeelStage
from tests.controller.insertion.world import ToyWorld, make_machine, path, toy_config


def feeling() -> MachineConfig:
    """The toy world's configuration with FEEL on."""
    config = toy_config()
    return replace(config, feel=replace(config.feel, enabled=True))


def _tip_error_in_search_m(world: ToyWorld, machine) -> float:
    """How far the plug's true tip is from the search pattern's point, 0.5 s into SEARCH."""
    world.run_until(machine, Phase.SEARCH)
    until = world.t_s + 0.5
    while world.t_s < until:
        world.step(machine)
    target = machine.hole_xyz[:2] + machine.pattern_offset_b(machine.memory.search_s_m)[:2]
    return float(np.linalg.norm(world.tip[:2] - target))


@pytest.mark.parametrize("tilt", [-0.06, 0.05])
def test_feel_finds_the_tilt_in_the_hand_and_the_search_follows_the_true_tip(tilt):
    world = ToyWorld(grasp_tilt_rad=tilt)
    machine = make_machine(world, feeling())
    error_m = _tip_error_in_search_m(world, machine)
    assert machine.grasp is not None
    assert machine.grasp.tilt_rad == pytest.approx(tilt, abs=0.005)
    assert error_m < 0.15e-3
    (published,) = machine.in_hand_estimates  # the width plane's, as the machine keeps it
    assert (published.plane, published.method, published.kept) == ("width", "rock", True)
    assert published.tilt_rad == machine.grasp.tilt_rad
    assert published.tip_offset_m == machine.grasp.tip_t[0]
    assert path(machine)[1:4] == [
        ("APPROACH", "FEEL", "first_contact"),
        ("FEEL", "APPROACH", "grasp_felt"),
        ("APPROACH", "SEARCH", "surface_contact"),
    ]
    assert world.run_until(machine, Phase.DONE) is Phase.DONE


def test_without_the_torque_the_tilt_is_not_found_and_the_search_misses_the_true_tip():
    world = ToyWorld(grasp_tilt_rad=0.05, edge_torque=0.0)
    machine = make_machine(world, feeling())
    rules = []
    while machine.phase is not Phase.SEARCH and world.t_s < 30.0:
        rules.append(world.step(machine).rule)
    assert machine.grasp is None  # the nominal grasp kept
    assert machine.in_hand_estimates == ()
    assert rules.count("feel.reverse") == 1  # the other way, once
    assert rules.count("feel.no_flat_face") == 1
    error_m = _tip_error_in_search_m(world, machine)
    assert error_m > 0.4e-3  # the lever times the tilt: 12 mm x 0.05 rad


def test_feel_rocks_toward_the_flat_face_first():
    world = ToyWorld(grasp_tilt_rad=0.05)
    machine = make_machine(world, feeling())
    world.run_until(machine, Phase.FEEL)
    while machine.stage is not FeelStage.ROCK:
        world.step(machine)
    start = world.rotation
    for _ in range(10):
        world.step(machine)
    turned = (world.rotation * start.inv()).as_rotvec()
    # the tilt is reached turning about B y (the axis across the opening's width at yaw 0)
    assert np.sign(turned[1]) == np.sign(0.05) and abs(turned[1]) > 0.01


def test_feel_is_off_by_default_and_the_run_goes_straight_to_search():
    world = ToyWorld(grasp_tilt_rad=0.05)
    machine = make_machine(world)
    assert world.run_until(machine, Phase.DONE) is Phase.DONE
    assert ("APPROACH", "SEARCH", "surface_contact") == path(machine)[1]
    assert machine.grasp is None


def test_a_regrasp_feels_again():
    world = ToyWorld(grasp_tilt_rad=0.05)
    machine = make_machine(world, feeling())
    world.run_until(machine, Phase.SEARCH)
    world.slip_gross = True
    world.run_until(machine, Phase.GRASP, max_s=world.t_s + 0.1)
    world.slip_gross = False
    assert machine.grasp is None  # the new grasp is not the one felt
    assert world.run_until(machine, Phase.DONE) is Phase.DONE
    feels = [t for t in path(machine) if t[1] == "FEEL"]
    assert len(feels) == 2 and machine.grasp is not None
