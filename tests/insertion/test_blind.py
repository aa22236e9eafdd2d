"""The blind baseline: its definition, its pattern of pushes, and its failure paths, in the
toy world (kinematic TCP; the blind machine reads no tactile signal)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from controller.insertion.blind import BLIND, BlindConfig, BlindMachine
from controller.insertion.definition import check_definition
from controller.insertion.interface import Phase
from controller.insertion.machine_config import GripperSettings
from controller.run.task import load_task
from core.config import ConfigError
from tests.insertion.world import ToyWorld

SMALL = BlindConfig(GripperSettings(), pitch_m=0.001, half_width_m=0.001, step_m=0.001,
                    timeout_s=60.0)  # fmt: skip


def run(world: ToyWorld, machine: BlindMachine, max_s: float = 80.0) -> list[np.ndarray]:
    """Step to a terminal phase; the tip's positions at the bottom of each push."""
    bottoms = []
    while world.t_s < max_s and machine.phase not in (Phase.DONE, Phase.FAILED):
        before = machine._stage
        world.step(machine)
        if before == "push" and machine._stage == "dwell":
            bottoms.append(world.tip.copy())
    return bottoms


def test_the_definition_is_checked_and_sound():
    check_definition(BLIND)
    assert {Phase.GRASP, Phase.DONE, Phase.FAILED} <= set(BLIND.phases)


def test_it_pushes_at_every_pattern_point_then_releases_and_retracts():
    world = ToyWorld()
    machine = BlindMachine(SMALL, world.plug, world.hole)
    bottoms = run(world, machine)
    assert [t.target for t in machine.transitions] == [
        Phase.APPROACH, Phase.SEARCH, Phase.RELEASE, Phase.RETRACT, Phase.DONE,
    ]  # fmt: skip
    assert len(bottoms) == machine._points >= 3
    hole = np.array([world.hole.x_m, world.hole.y_m])
    for tip in bottoms:  # each push goes to the push depth, within the pattern's square
        assert tip[2] == pytest.approx(world.hole.z_m - SMALL.push_depth_m, abs=3e-4)
        assert np.all(np.abs(tip[:2] - hole) <= SMALL.half_width_m * np.sqrt(2) + 3e-4)
    assert not world.gripper_holding  # released at the end


def test_its_grasp_travels_fast_to_just_above_the_plug_then_closes_slowly():
    world = ToyWorld()
    machine = BlindMachine(SMALL, world.plug, world.hole)
    world.run_until(machine, Phase.APPROACH)
    targets = [c.gripper for c in world.commands if c.gripper is not None]
    g = SMALL.gripper
    assert [(t.width_m, t.speed_m_s) for t in targets] == [
        (pytest.approx(world.plug.thickness_m + g.preclose_gap_m), g.preclose_speed_m_s),
        (g.close_width_m, g.close_speed_m_s),
    ]


def test_it_fails_on_the_timeout_and_on_a_device_fault():
    world = ToyWorld()
    machine = BlindMachine(replace(SMALL, timeout_s=2.0), world.plug, world.hole)
    run(world, machine)
    assert machine.phase is Phase.FAILED and machine.transitions[-1].reason == "timeout"
    world = ToyWorld()
    machine = BlindMachine(SMALL, world.plug, world.hole)
    world.run_until(machine, Phase.SEARCH)
    world.arm_error = 31
    run(world, machine)
    assert machine.transitions[-1].reason == "device_fault"


def test_a_bad_value_names_its_key():
    with pytest.raises(ConfigError, match="key 'blind.step_m'"):
        load_task("usb_c", ["blind.step_m=-1"])
