"""The blind baseline: its definition, its pressed sweeps (one per yaw offset), and its
failure paths, in the toy world (kinematic TCP; the blind machine reads no tactile signal)."""

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

SMALL = BlindConfig(GripperSettings(), pitch_m=0.001, half_width_m=0.001, press_m=0.004,
                    sweep_speed_m_s=0.005, descend_speed_m_s=0.005, yaw_step_rad=0.02,
                    yaw_range_rad=0.02,
                    timeout_s=60.0)  # fmt: skip


def run(world: ToyWorld, machine: BlindMachine, max_s: float = 80.0) -> list[tuple]:
    """Step to a terminal phase; (tip position, yaw offset) of every tick of a sweep."""
    swept = []
    while world.t_s < max_s and machine.phase not in (Phase.DONE, Phase.FAILED):
        world.step(machine)
        if machine._stage == "sweep":
            swept.append((world.tip.copy(), machine.config.yaw_offsets[machine._pass]))
    return swept


def test_the_definition_is_checked_and_sound():
    check_definition(BLIND)
    assert {Phase.GRASP, Phase.DONE, Phase.FAILED} <= set(BLIND.phases)


def test_the_yaw_offsets_alternate_within_the_range():
    assert SMALL.yaw_offsets == (0.0, 0.02, -0.02)
    assert replace(SMALL, yaw_range_rad=0.0).yaw_offsets == (0.0,)
    assert replace(SMALL, yaw_range_rad=0.05).yaw_offsets == (0.0, 0.02, -0.02, 0.04, -0.04)


def test_it_sweeps_the_pattern_pressed_once_per_yaw_then_releases_and_retracts():
    world = ToyWorld()
    machine = BlindMachine(SMALL, world.plug, world.hole)
    swept = run(world, machine)
    assert [t.target for t in machine.transitions] == [
        Phase.APPROACH, Phase.SEARCH, Phase.RELEASE, Phase.RETRACT, Phase.DONE,
    ]  # fmt: skip
    assert {yaw for _, yaw in swept} == set(SMALL.yaw_offsets)
    hole = np.array([world.hole.x_m, world.hole.y_m])
    tips = np.array([tip for tip, _ in swept])
    # pressed: the tip target press_m below the surface (the kinematic toy has no board)
    assert np.median(tips[:, 2]) == pytest.approx(world.hole.z_m - SMALL.press_m, abs=3e-4)
    reach = np.linalg.norm(tips[:, :2] - hole, axis=1)
    assert reach.max() <= SMALL.half_width_m * np.sqrt(2) + 3e-4  # within the pattern
    assert reach.max() >= SMALL.half_width_m  # and out to its edge
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
    with pytest.raises(ConfigError, match="key 'blind.press_m'"):
        load_task("usb_c", ["blind.press_m=-1"])
