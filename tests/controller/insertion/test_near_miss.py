"""The touch spiral's near misses: the tilt torques' jump over the sweep's baseline, and the
retrace on the ring half a pitch outside that turns a rim crossed between two rings into a
catch (the toy world: a catch region narrower than the pitch, a rim around it)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from controller.insertion.force_reading import TactileAxialForce
from controller.insertion.interface import Phase
from controller.insertion.spiral import SpiralMachine, TouchSpiralConfig
from controller.insertion.spiral.spiral_near_miss import (
    NearMissDetector,
    NearMissSettings,
    side_named_b,
)
from controller.insertion.spiral.spiral_search import SearchStage
from controller.run.task import load_task
from core.config import ConfigError
from tests.controller.insertion.test_blind import reasons
from tests.controller.insertion.test_touch_spiral import SPIRAL, run, touch_world

SLOW = replace(SPIRAL, yaw_range_rad=0.0, sweep_speed_m_s=0.002)  # the toy's catch needs 0.1 s
ON = NearMissSettings(enabled=True, tilt_jump_nm=0.0015, back_m=0.002,
                      outward_m=SPIRAL.pitch_m / 2, per_pass=3)  # fmt: skip


def spiral(world, config: TouchSpiralConfig) -> SpiralMachine:
    """The touch spiral on ``config``, its near misses as the product's are wired."""
    reading = TactileAxialForce(config.axial_weights, config.force_window)
    return SpiralMachine(config, world.plug, world.hole, reading, near_misses=config.near_miss)


def between_rings_world(**kwargs):
    """An opening whose catch region (0.1 mm) lies halfway between two of the spiral's
    rings (at 1.0 and 1.5 mm from the pattern's centre, along its u) with a rim that both
    rings cross: only a ring half a pitch outside reaches it. No drag torque: the toy's
    turns with the spiral's direction at full size (the scene's is under the jump)."""
    pitch = SPIRAL.pitch_m
    offset = (2.5 * pitch, 0.0)
    return touch_world(
        hole_offset_m=offset, hole_radius_m=0.0001, rim_width_m=0.0003, friction=0.0, **kwargs
    )


def test_a_jump_over_the_baseline_is_a_near_miss_and_each_frame_counts_once():
    detector = NearMissDetector(ON)
    quiet = [np.array([0.0002 * (-1) ** k, 0.0001, 0.0]) for k in range(5)]
    assert all(detector.jump(tau, 0.04 * k) is None for k, tau in enumerate(quiet))
    jump = np.array([0.0018, 0.0, 0.0])  # 1.8 mN*m about T x
    change = detector.jump(jump, 0.20)
    # less the baseline: the median of the 5 quiet frames, (0.0002, 0.0001) (3 of 5 positive)
    assert change == pytest.approx([0.0018 - 0.0002, -0.0001])
    assert detector.jump(jump, 0.20) is None  # the same frame again
    assert detector.jump(np.array([0.0, 0.0, 0.01]), 0.24) is None  # about T z: not a tilt
    assert detector.jump(np.array([0.001, 0.001, 0.0]), 0.28) is None  # 1.4 mN*m: under


def test_a_new_sweep_takes_its_own_baseline():
    detector = NearMissDetector(ON)
    for k in range(5):
        detector.jump(np.zeros(3), 0.04 * k)
    detector.reset()
    far = np.array([0.01, 0.0, 0.0])
    assert all(detector.jump(far, 1.0 + 0.04 * k) is None for k in range(6))


@pytest.mark.parametrize("yaw_deg", [0.0, 30.0, -120.0])
@pytest.mark.parametrize("tip_from_opening", [(1.0, 0.0), (0.0, -1.0), (0.6, 0.8)])
def test_the_side_a_jump_names_is_where_the_board_does_not_bear_the_face(yaw_deg, tip_from_opening):
    # the tip off the opening along u (B): the board bears the face on the +u side, and the
    # torque on the plug changes along -(u x z_B) (near_miss_sides' convention)
    u = np.array([*tip_from_opening, 0.0])
    change_b = -np.cross(u, [0.0, 0.0, 1.0])
    t2b = Rotation.from_euler("z", math.radians(yaw_deg)) * Rotation.from_euler("x", math.pi)
    change_t = t2b.inv().apply(change_b)
    assert side_named_b(0.002 * change_t[:2], t2b) == pytest.approx(-u[:2])


def test_without_near_misses_a_rim_between_the_rings_is_crossed_and_the_pass_goes_on():
    world = between_rings_world(rim_torque=0.005)
    machine = spiral(world, SLOW)
    run(world, machine, max_s=40.0)
    assert "caught" not in reasons(machine)
    assert reasons(machine)[2] == "pattern_done"


def test_a_near_miss_is_retraced_half_a_pitch_outside_and_caught():
    world = between_rings_world(rim_torque=0.005)
    config = replace(SLOW, near_miss=ON)
    machine = spiral(world, config)
    hole = world.hole_xy
    retraced = []
    while world.t_s < 40.0 and machine.phase not in (Phase.INSERT, Phase.RELEASE):
        before = (machine.stage, machine.memory.s_m)
        world.step(machine)
        if before[0] is SearchStage.SWEEP and machine.stage is SearchStage.RETRACE:
            assert machine.memory.s_m < before[1]  # back along the pattern
            retraced.append(before[1])
        if machine.stage is SearchStage.RETRACE:
            # on the ring half a pitch out: the tip's target that far from the pattern's
            u, v = machine._pattern.offset(machine.memory.s_m)
            target = machine.tip_target(machine.memory.s_m, 0.0)[:2]
            nominal = np.array([world.hole.x_m, world.hole.y_m])
            assert np.linalg.norm(target - nominal) == pytest.approx(
                math.hypot(u, v) + ON.outward_m, abs=1e-9
            )
    assert retraced, "no near miss"
    assert reasons(machine)[2] == "caught"
    assert np.linalg.norm(world.tip[:2] - hole) < world.hole_radius_m
    assert machine.memory.retrace_until_m is None  # the catch ends the retrace


def side_world(catch_m: float, rim_width_m: float):
    """A catch region (0.1 mm) ``catch_m`` from the pattern's centre along its +y, where the
    pattern's rings pass at 1.125 and 1.625 mm, with a rim ``rim_width_m`` wide around it that
    names the side (the toy's tactile torques carry it about T x, so the side lies along y)."""
    return touch_world(
        hole_offset_m=(0.0, catch_m), hole_radius_m=0.0001, rim_width_m=rim_width_m,
        friction=0.0, rim_torque=0.005, rim_names_side=True,
    )  # fmt: skip


def retraces_inward(world, config) -> tuple[list[bool], SpiralMachine]:
    """Run the spiral on ``config`` in ``world``: at each tick of a retrace whether its ring
    lies inside the pattern's; the machine."""
    machine = spiral(world, config)
    inward = []
    while world.t_s < 40.0 and machine.phase not in (Phase.INSERT, Phase.RELEASE):
        world.step(machine)
        if machine.stage is SearchStage.RETRACE:
            u, v = machine._pattern.offset(machine.memory.s_m)
            target = machine.tip_target(machine.memory.s_m, 0.0)[:2]
            nominal = np.array([world.hole.x_m, world.hole.y_m])
            inward.append(bool(np.linalg.norm(target - nominal) < math.hypot(u, v)))
    return inward, machine


TOWARD_SIDE = replace(SLOW, near_miss=replace(ON, toward_side=True))


def test_a_rim_crossed_inside_the_catch_names_the_outside():
    # the ring at 1.125 mm crosses the rim 0.25 mm inside the catch: out to 1.375 mm
    inward, machine = retraces_inward(side_world(0.001375, 0.0003), TOWARD_SIDE)
    assert inward and not any(inward)
    assert reasons(machine)[2] == "caught"


def test_a_rim_crossed_outside_the_catch_names_the_inside_where_outward_misses():
    # only the ring at 1.625 mm crosses the rim, 0.18 mm outside the catch at 1.445 mm: the
    # retrace half a pitch inside (1.375 mm) reaches the catch, one outside (1.875 mm) does not
    inward, machine = retraces_inward(side_world(0.001445, 0.0002), TOWARD_SIDE)
    assert inward and all(inward)
    assert reasons(machine)[2] == "caught"
    inward, machine = retraces_inward(side_world(0.001445, 0.0002), replace(SLOW, near_miss=ON))
    assert inward and not any(inward)
    assert "caught" not in reasons(machine)


def test_a_quiet_rim_starts_no_retrace():
    world = between_rings_world(rim_torque=0.0)
    config = replace(SLOW, near_miss=ON)
    machine = spiral(world, config)
    run(world, machine, max_s=40.0)
    assert not any(c.rule == "search.retrace" for c in world.commands)
    assert "caught" not in reasons(machine)


def test_the_retraces_of_a_pass_are_capped():
    world = between_rings_world(rim_torque=0.005)
    world.hole_radius_m = 0.0  # nothing to catch: the rim only
    config = replace(SLOW, near_miss=replace(ON, per_pass=2))
    machine = spiral(world, config)
    run(world, machine, max_s=40.0)
    assert machine.memory.retraces == {0: 2}


@pytest.mark.parametrize(
    ("key", "value"),
    [("tilt_jump_nm", "0"), ("median_frames", "1"), ("outward_m", "0.01"), ("per_pass", "-1")],
)
def test_near_miss_settings_out_of_range_are_refused(key, value):
    with pytest.raises(ConfigError, match=f"touch_spiral.near_miss.{key}"):
        load_task("usb_c", [f"touch_spiral.near_miss.{key}={value}"])


def test_a_rim_felt_before_the_same_ring_catches_is_not_retraced():
    world = touch_world(hole_offset_m=(2.0 * SPIRAL.pitch_m, 0.0), hole_radius_m=0.0001,
                        rim_width_m=0.0003, friction=0.0, rim_torque=0.005)  # fmt: skip
    machine = spiral(world, replace(SLOW, near_miss=ON))
    felt = False
    while world.t_s < 40.0 and machine.phase is not Phase.INSERT:
        world.step(machine)
        felt = felt or machine.memory.near_miss_m is not None
    assert felt  # the rim was felt on the way in
    assert reasons(machine)[2] == "caught"
    assert not any(c.rule == "search.retrace" for c in world.commands)


def test_near_misses_are_retraced_from_the_pass_named_on():
    world = between_rings_world(rim_torque=0.005)
    config = replace(SLOW, yaw_range_rad=0.02, near_miss=replace(ON, from_pass=1))
    machine = spiral(world, config)
    passes_retraced = set()
    while world.t_s < 80.0 and machine.phase not in (Phase.INSERT, Phase.RELEASE):
        world.step(machine)
        if machine.stage is SearchStage.RETRACE:
            passes_retraced.add(machine.memory.pass_index)
    assert passes_retraced == {1}
    assert reasons(machine)[2] == "caught"
