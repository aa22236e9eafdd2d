"""The blind baseline: its definition, its force-threshold sweeps (one per yaw offset), the
catch, the push and the jam, and its failure paths, in the toy world (kinematic TCP; the
blind machine reads no tactile signal, only the arm's pose and its F/T force)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from controller.insertion.definition import check_definition
from controller.insertion.interface import Phase
from controller.insertion.machine_config import GripperSettings
from controller.insertion.spiral import NO_FORCE, SPIRAL, SpiralConfig, SpiralMachine
from controller.insertion.spiral.spiral_search import SearchStage, plan_passes
from controller.run.task import load_task
from core.config import ConfigError
from tests.controller.insertion.world import ToyWorld

SMALL = SpiralConfig(GripperSettings(), pitch_m=0.0005, half_width_m=0.002, touch_force_n=1.0,
                    press_force_n=2.0, stop_force_n=6.0, sweep_speed_m_s=0.01,
                    descend_speed_m_s=0.005, yaw_step_rad=0.02, yaw_range_rad=0.02,
                    timeout_s=60.0)  # fmt: skip
NO_OPENING = dict(hole_offset_m=(0.01, 0.01))  # outside the pattern: the board everywhere


def run(world: ToyWorld, machine: SpiralMachine, max_s: float = 80.0) -> list[tuple]:
    """Step to a terminal phase; (tip, yaw offset, force) of every tick of a sweep."""
    swept = []
    while world.t_s < max_s and machine.phase not in (Phase.DONE, Phase.FAILED):
        world.step(machine)
        if machine.phase is Phase.SEARCH and machine.stage is SearchStage.SWEEP:
            force = world.observe().arm.external_force_n[2]
            yaw = machine.search_pass.yaw_offset_rad
            swept.append((world.tip.copy(), yaw, force))
    return swept


def reasons(machine: SpiralMachine) -> list[str]:
    return [t.reason for t in machine.transitions]


def test_the_definition_is_checked_and_sound():
    check_definition(SPIRAL)
    assert {Phase.GRASP, Phase.INSERT, Phase.DONE, Phase.FAILED} <= set(SPIRAL.phases)


def test_the_yaw_offsets_alternate_within_the_range():
    assert SMALL.yaw_offsets == (0.0, 0.02, -0.02)
    assert replace(SMALL, yaw_range_rad=0.0).yaw_offsets == (0.0,)
    assert replace(SMALL, yaw_range_rad=0.05).yaw_offsets == (0.0, 0.02, -0.02, 0.04, -0.04)


def test_an_inner_half_width_sweeps_the_inner_spiral_at_every_yaw_before_the_rest():
    rings = replace(SMALL, inner_half_width_m=0.001)
    passes = plan_passes(rings)
    assert [p.yaw_offset_rad for p in passes] == list(SMALL.yaw_offsets) * 2
    inner, whole = passes[0].end_m, passes[-1].end_m
    assert [(p.start_m, p.end_m) for p in passes] == [(0.0, inner)] * 3 + [(inner, whole)] * 3
    assert 0.0 < inner < whole
    assert [(p.start_m, p.end_m) for p in plan_passes(SMALL)] == [(0.0, whole)] * 3
    world = ToyWorld(**NO_OPENING)
    machine = SpiralMachine(rings, world.plug, world.hole)
    swept = run(world, machine)
    assert reasons(machine)[-3:] == ["pattern_done", "released", "retracted"]
    hole = np.array([world.hole.x_m, world.hole.y_m])
    reach = np.array([np.linalg.norm(tip[:2] - hole) for tip, _, _ in swept])
    yaws = [yaw for _, yaw, _ in swept]
    far = int(np.argmax(reach > rings.inner_half_width_m * np.sqrt(2) + 3e-4))
    assert far > 0 and set(yaws[:far]) == set(SMALL.yaw_offsets)  # every yaw, all near
    assert reach.max() >= SMALL.half_width_m  # then out to the edge


def test_interleaved_passes_turn_the_spiral_by_half_a_turn_at_every_other_yaw_step():
    both = replace(SMALL, inner_half_width_m=0.001, interleave=True)
    assert [p.pattern_turn_rad for p in plan_passes(both)] == [0.0, np.pi, np.pi] * 2
    assert {p.pattern_turn_rad for p in plan_passes(SMALL)} == {0.0}
    # neighbouring yaws (an opening between them is within reach of both) never share rings
    wide = replace(SMALL, interleave=True, yaw_range_rad=0.07)
    turn = {p.yaw_offset_rad: p.pattern_turn_rad for p in plan_passes(wide)}
    yaws = sorted(turn)
    assert len(yaws) == 7
    assert all(turn[a] != turn[b] for a, b in zip(yaws, yaws[1:], strict=False))
    world = ToyWorld(**NO_OPENING)
    machine = SpiralMachine(replace(SMALL, interleave=True), world.plug, world.hole)
    swept = run(world, machine)
    hole = np.array([world.hole.x_m, world.hole.y_m])
    # the second pass's rings lie between the first's: at a swept radius, the first pass's
    # tip and the second's are on opposite sides of the opening's centre
    by_yaw = {yaw: np.array([tip[:2] - hole for tip, y, _ in swept if y == yaw]) for yaw in
              SMALL.yaw_offsets}  # fmt: skip
    first, second = by_yaw[SMALL.yaw_offsets[0]], by_yaw[SMALL.yaw_offsets[1]]
    k = len(first) // 2
    nearest = second[np.argmin(np.linalg.norm(second + first[k], axis=1))]
    assert np.linalg.norm(nearest + first[k]) < 1.2e-4  # the point turned by half a turn
    assert np.linalg.norm(nearest - first[k]) > 1e-3


@pytest.mark.parametrize(
    "change", [dict(inner_half_width_m=0.002), dict(inner_half_width_m=0.001, pattern="raster")]
)
def test_an_inner_half_width_must_be_inside_the_spiral(change):
    with pytest.raises(ValueError, match="key 'inner_half_width_m'"):
        replace(SMALL, **change)


def test_without_an_opening_it_sweeps_pressed_once_per_yaw_then_releases_and_retracts():
    world = ToyWorld(**NO_OPENING)
    machine = SpiralMachine(SMALL, world.plug, world.hole)
    swept = run(world, machine)
    assert reasons(machine) == [
        "grasped", "above_the_opening", "pattern_done", "released", "retracted",
    ]  # fmt: skip
    assert {yaw for _, yaw, _ in swept} == set(SMALL.yaw_offsets)
    forces = np.array([force for _, _, force in swept])
    # the admittance holds the press (after each pass's first settling)
    assert np.median(forces) == pytest.approx(SMALL.press_force_n, abs=0.2)
    hole = np.array([world.hole.x_m, world.hole.y_m])
    reach = np.linalg.norm(np.array([tip[:2] for tip, _, _ in swept]) - hole, axis=1)
    assert reach.max() <= SMALL.half_width_m * np.sqrt(2) + 3e-4  # within the pattern
    assert reach.max() >= SMALL.half_width_m  # and out to its edge
    assert not world.gripper_holding  # released at the end


def test_over_the_opening_it_catches_pushes_to_the_floor_and_releases():
    world = ToyWorld()  # the opening 1.5 mm off the nominal, 12 mm deep
    machine = SpiralMachine(SMALL, world.plug, world.hole)
    run(world, machine)
    assert reasons(machine) == [
        "grasped", "above_the_opening", "caught", "bottomed", "released", "retracted",
    ]  # fmt: skip
    bottomed = machine.transitions[3]
    assert bottomed.rule == "force"
    rules = [c.rule for c in world.commands]
    expected = {"search.tare", "search.touch", "search.sweep", "search.probe", "insert.push"}
    assert expected <= set(rules)
    # the push ended on the floor: the tip was held down to it, the force at the stop
    assert min(c for c in world_tip_heights(world)) == pytest.approx(
        world.hole.z_m - world.depth_limit_m - SMALL.stop_force_n / world.k_arm_n_m, abs=3e-4
    )


def test_a_plug_that_goes_into_the_opening_on_the_way_down_is_pushed_home_not_swept():
    world = ToyWorld(hole_offset_m=(0.0, 0.0))  # the opening under the pattern's start
    machine = SpiralMachine(SMALL, world.plug, world.hole)
    run(world, machine)
    assert reasons(machine) == [
        "grasped", "above_the_opening", "fell_in", "bottomed", "released", "retracted",
    ]  # fmt: skip
    rules = {c.rule for c in world.commands}
    assert "search.sweep" not in rules and "insert.push" in rules
    # no touch before: the TCP went fall_in_m below the nominal board's touch height
    assert min(world_tip_heights(world)) < world.hole.z_m - SMALL.fall_in_m


def test_a_plug_that_sinks_into_the_opening_before_the_press_settles_is_pushed_home():
    world = ToyWorld(**NO_OPENING)
    machine = SpiralMachine(SMALL, world.plug, world.hole)
    while machine.stage is not SearchStage.SWEEP:
        world.step(machine)
    assert machine.memory.press_z_m is None  # the press not yet settled
    world.board = False  # the tip slides down into the opening: nothing holds it up
    start_s = world.t_s
    run(world, machine, max_s=start_s + 10.0)
    assert reasons(machine)[2] == "fell_in"  # not a probe at the arm's floor until the time ends
    sank = machine.transitions[2]
    assert machine.phase is not Phase.SEARCH and sank.t_s - start_s < 2.0
    # it took the TCP fall_in_m below its height at the touch to say so
    touch_z = machine.memory.touch_z_m
    assert touch_z is not None and machine.memory.press_z_m == touch_z
    assert min(world_tip_heights(world)) < world.hole.z_m - SMALL.fall_in_m


@pytest.mark.parametrize("sink_m", [0.0, 0.002])
def test_a_tip_that_sinks_while_the_press_holds_is_in_only_with_sink_m(sink_m):
    # the press settled, the surface under the tip gives way slowly (a plug dragged into the
    # opening's mouth, the walls bearing the press): the force never drops, the tip goes down
    world = ToyWorld(**NO_OPENING)
    machine = SpiralMachine(replace(SMALL, sink_m=sink_m), world.plug, world.hole)
    while machine.memory.press_z_m is None:
        world.step(machine)
    start_s = world.t_s
    while world.t_s < start_s + 4.0 and machine.phase is Phase.SEARCH:
        world.floor_drop_m = min(0.004, world.floor_drop_m + 2e-5)  # 2 mm/s, to 4 mm
        world.step(machine)
    if sink_m:
        assert reasons(machine)[2] == "sank"
        # about sink_m under its height at the press (the press's height is the TCP's when
        # the force first came within the settle band, up to 0.4 mm above the full press)
        assert 0.0015 <= world.floor_drop_m < 0.003
    else:
        assert machine.phase is Phase.SEARCH and "probe" not in {c.rule for c in world.commands}


def test_a_catch_on_a_board_met_late_is_a_catch_not_a_fall_in():
    # the board 2.5 mm low (or the plug short in the fingers): pressed, the TCP stands over
    # fall_in_m below the nominal board's touch, but not below its own touch
    world = ToyWorld(floor_drop_m=0.0025)
    machine = SpiralMachine(SMALL, world.plug, world.hole)
    run(world, machine)
    assert reasons(machine)[2:4] == ["caught", "bottomed"]


def test_a_board_met_late_whose_force_is_rising_is_a_touch_not_a_fall_in():
    # the board 0.7 mm short of the fall-in depth: there the force reads ~0.6 N (0.7 N, the
    # window's mean behind it), short of the touch's 1 N
    late = dict(floor_drop_m=SMALL.fall_in_m - 0.0007, **NO_OPENING)
    world = ToyWorld(**late)
    lagging = SpiralMachine(SMALL, world.plug, world.hole)
    run(world, lagging, max_s=10.0)
    assert "fell_in" in reasons(lagging)  # any force under the touch's: taken for a fall-in
    world = ToyWorld(**late)
    felt = SpiralMachine(replace(SMALL, fall_in_force_n=0.5), world.plug, world.hole)
    run(world, felt, max_s=10.0)
    assert "fell_in" not in reasons(felt)
    assert "search.sweep" in {c.rule for c in world.commands}  # touched the board, swept


def world_tip_heights(world: ToyWorld) -> list[float]:
    """The tip's heights the toy went through (from the commanded twists, replayed)."""
    heights, z = [], world.hole.z_m + 0.04
    for command in world.commands:
        if command.twist is not None:
            z += command.twist.linear_m_s[2] * 0.01
        heights.append(z)
    return heights


def test_a_catch_that_stops_short_of_the_entry_is_a_jam_and_the_sweep_goes_on():
    world = ToyWorld(depth_limit_m=0.0015)  # an opening 1.5 mm deep: never entry_m (2 mm) in
    machine = SpiralMachine(SMALL, world.plug, world.hole)
    run(world, machine)
    assert "caught" in reasons(machine) and "jammed" in reasons(machine)
    assert "bottomed" not in reasons(machine)
    assert reasons(machine)[-3:] == ["pattern_done", "released", "retracted"]


@pytest.mark.parametrize("lift_speed_m_s", [0.004, 0.02])
def test_after_a_jam_it_backs_up_to_the_press_at_the_lift_speed(lift_speed_m_s):
    world = ToyWorld(depth_limit_m=0.0015)  # every catch jams
    config = replace(SMALL, lift_speed_m_s=lift_speed_m_s)
    machine = SpiralMachine(config, world.plug, world.hole)
    run(world, machine)
    lifts = [c.twist.linear_m_s[2] for c in world.commands if c.rule == "insert.lift"]
    assert lifts and max(lifts) == pytest.approx(lift_speed_m_s)  # up (B z) at that speed
    assert "jammed" in reasons(machine)


def test_the_tare_takes_up_the_sensor_bias():
    world = ToyWorld(force_bias_n=3.0)  # above the touch force: untared it would "touch" at once
    machine = SpiralMachine(SMALL, world.plug, world.hole)
    run(world, machine)
    assert "bottomed" in reasons(machine)


def test_an_arm_without_a_force_reading_fails_at_once_naming_it():
    world = ToyWorld(arm_force=False)
    machine = SpiralMachine(SMALL, world.plug, world.hole)
    run(world, machine)
    assert machine.phase is Phase.FAILED
    assert (machine.transitions[-1].reason, machine.transitions[-1].rule) == (
        "device_fault",
        NO_FORCE,
    )


def test_its_grasp_travels_fast_to_just_above_the_plug_then_closes_slowly():
    world = ToyWorld()
    machine = SpiralMachine(SMALL, world.plug, world.hole)
    world.run_until(machine, Phase.APPROACH)
    targets = [c.gripper for c in world.commands if c.gripper is not None]
    g = SMALL.gripper
    assert [(t.width_m, t.speed_m_s) for t in targets] == [
        (pytest.approx(world.plug.thickness_m + g.preclose_gap_m), g.preclose_speed_m_s),
        (g.close_width_m, g.close_speed_m_s),
    ]


def test_it_fails_on_the_timeout_and_on_a_device_fault():
    world = ToyWorld()
    machine = SpiralMachine(replace(SMALL, timeout_s=2.0), world.plug, world.hole)
    run(world, machine)
    assert machine.phase is Phase.FAILED and machine.transitions[-1].reason == "timeout"
    world = ToyWorld()
    machine = SpiralMachine(SMALL, world.plug, world.hole)
    world.run_until(machine, Phase.SEARCH)
    world.arm_error = 31
    run(world, machine)
    assert machine.transitions[-1].reason == "device_fault"


def test_a_bad_value_names_its_key():
    with pytest.raises(ConfigError, match="key 'blind.press_force_n'"):
        load_task("usb_c", ["blind.press_force_n=-1"])


def test_forces_out_of_order_are_refused_naming_the_keys():
    with pytest.raises(ConfigError, match="'touch_force_n', 'press_force_n', 'stop_force_n'"):
        load_task("usb_c", ["blind.stop_force_n=1.5"])
