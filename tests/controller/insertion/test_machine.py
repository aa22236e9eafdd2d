"""The insertion machine on synthetic observation sequences (tests/controller/insertion/world.py):
every transition and every failure path."""

from dataclasses import replace

import numpy as np
import pytest

from controller.insertion.interface import Phase
from controller.insertion.machine_config import (
    BackoffSettings,
    GripperSettings,
    MachineConfig,
    SearchSettings,
    SlipSettings,
    Timeouts,
)
from controller.insertion.motion import lowest_edge
from controller.insertion.phases.align import AlignStage
from controller.insertion.phases.search import SearchStage
from controller.insertion.search_path import SearchPattern
from core.spatial import tilt_of_rotation
from tests.controller.insertion.world import ToyWorld, make_machine, path, toy_config

HAPPY = [
    ("GRASP", "APPROACH", "grasped_and_zeroed"),
    ("APPROACH", "SEARCH", "surface_contact"),
    ("SEARCH", "ALIGN", "hole_found"),
    ("ALIGN", "INSERT", "aligned"),
    ("INSERT", "RELEASE", "depth_reached"),
    ("RELEASE", "RETRACT", "released"),
    ("RETRACT", "DONE", "retracted"),
]


def config(**parts) -> MachineConfig:
    return replace(toy_config(), **parts)


@pytest.mark.parametrize(
    ("pattern", "offset"),
    [("spiral", (0.0012, -0.0009)), ("raster", (0.0012, -0.0009)), ("spiral", (-0.002, -0.001))],
)
def test_happy_path_reaches_done_through_every_phase(pattern, offset):
    world = ToyWorld(hole_offset_m=offset)
    machine = make_machine(world, config(search=replace(SearchSettings(), pattern=pattern)))
    assert world.run_until(machine, Phase.DONE) is Phase.DONE
    assert path(machine) == HAPPY
    times = [t.t_s for t in machine.transitions]
    assert times == sorted(times)
    assert world.rezero_count == 1
    grippers = [c.gripper for c in world.commands if c.gripper is not None]
    preclose_m = world.plug.thickness_m + MachineConfig().gripper.preclose_gap_m
    assert [g.width_m for g in grippers] == pytest.approx(
        [preclose_m, 0.0, MachineConfig().gripper.open_width_m]
    )


def test_every_command_names_its_rule_and_the_hole_find_names_its_detector():
    world = ToyWorld(hole_offset_m=(0.0012, -0.0009))
    machine = make_machine(world, config())
    world.run_until(machine, Phase.DONE)
    rules = [c.rule for c in world.commands]
    assert all(rules), "a command without its rule"
    assert {r.split(".")[0] for r in rules} == {src.lower() for src, _, _ in HAPPY}
    assert "search.drag" in rules and "insert.depth_reached" in rules
    found = next(t for t in machine.transitions if t.reason == "hole_found")
    assert found.rule in {"torque_catch", "load_drop", "torque_catch+load_drop", "probe"}
    assert f"search.hole_found:{found.rule}" in rules
    aligned = rules.index("align.aligned")
    align_rules = [r for r in rules[:aligned] if r.startswith("align.")]
    stages = [r for i, r in enumerate(align_rules) if i == 0 or align_rules[i - 1] != r]
    # seek the wall, turn upright about the heel, (slide to the low end, sweep the yaw until
    # it enters,) servo
    assert stages[:4] == ["align.seek", "align.wall", "align.turn", "align.upright"]
    assert set(stages[4:]) <= {
        "align.width_slide", "align.end_wall", "align.width_done", "align.yaw_sweep",
        "align.entered", "align.entering", "align.twist_held", "align.torque_servo",
        "align.within_tolerance",
    }  # fmt: skip


def test_commands_are_bounded_twists_and_hold_still_while_grasping():
    world = ToyWorld()
    cfg = toy_config()
    machine = make_machine(world, cfg)
    world.run_until(machine, Phase.DONE)
    for command in world.commands:
        assert command.pose is None and command.twist is not None
        limits = cfg.limits
        linear, angular = command.twist.linear_m_s, command.twist.angular_rad_s
        assert np.linalg.norm(linear) <= limits.max_command_speed_m_s + 1e-12
        assert np.linalg.norm(angular) <= limits.max_command_angular_speed_rad_s + 1e-12
    grasp_ticks = int(machine.transitions[0].t_s / 0.01)
    assert all(c.twist == type(c.twist)() for c in world.commands[:grasp_ticks])


def test_grasp_settles_then_rezeroes_then_measures_the_baseline():
    world = ToyWorld(frame_every=3, zeroing_frames=4)
    cfg = toy_config()
    machine = make_machine(world, cfg)
    world.run_until(machine, Phase.APPROACH)
    rezero_tick = next(i for i, c in enumerate(world.commands) if c.rezero_tactile)
    close_tick = next(i for i, c in enumerate(world.commands) if c.gripper is not None)
    # the gripper moves for 0.15 s, then must hold for settle_s
    assert (rezero_tick - close_tick) * 0.01 >= 0.15 + cfg.gripper.settle_s - 0.011
    approach_tick = round(machine.transitions[0].t_s / 0.01)
    frames_after = (approach_tick - rezero_tick) / world.frame_every
    assert frames_after >= world.zeroing_frames + cfg.signals.baseline_frames - 1
    assert world.rezero_count == 1


def test_grasp_travels_fast_to_just_above_the_plug_then_closes_slowly():
    world = ToyWorld()
    cfg = toy_config()
    machine = make_machine(world, cfg)
    world.run_until(machine, Phase.APPROACH)
    first = world.commands[0]
    assert first.capture_open_tactile
    assert first.gripper.width_m == pytest.approx(
        world.plug.thickness_m + cfg.gripper.preclose_gap_m
    )
    assert first.gripper.speed_m_s == cfg.gripper.preclose_speed_m_s
    close_tick, close = next(
        (i, c) for i, c in enumerate(world.commands) if c.gripper is not None and i > 0
    )
    assert close.gripper.width_m == cfg.gripper.close_width_m
    assert close.gripper.speed_m_s == cfg.gripper.close_speed_m_s
    assert close_tick * 0.01 >= 0.15 - 1e-9  # not before the fast travel has ended


def test_a_gripper_already_near_the_plug_is_not_sent_a_pre_close():
    world = ToyWorld()
    world.gripper_width = world.plug.thickness_m + 0.0005
    machine = make_machine(world, toy_config())
    world.run_until(machine, Phase.APPROACH)
    assert world.commands[0].capture_open_tactile and world.commands[0].gripper is None


def test_approach_from_below_rises_before_moving_sideways():
    world = ToyWorld()
    machine = make_machine(world)
    world.run_until(machine, Phase.APPROACH)
    world.p = world.p + np.array([0.01, 0.0, -0.037])  # tip 3 mm above the board, 10 mm off
    start, rotation = world.p.copy(), world.rotation
    target_z = world.hole.z_m + MachineConfig().approach.height_m
    while world.tip[2] < target_z - 0.0005:
        world.step(machine)
        assert abs(world.p[0] - start[0]) < 1e-3  # no sideways travel while low
        # ... and no turning (the plug may be in the opening)
        assert (world.rotation * rotation.inv()).magnitude() < 1e-9
    assert world.run_until(machine, Phase.DONE) is Phase.DONE


def test_a_jam_backs_off_and_realigns_then_succeeds():
    world = ToyWorld(jam_depth_m=0.002, jams=1)
    machine = make_machine(world)
    assert world.run_until(machine, Phase.DONE) is Phase.DONE
    assert path(machine)[3:8] == [
        ("ALIGN", "INSERT", "aligned"),
        ("INSERT", "BACKOFF", "jam"),
        ("BACKOFF", "ALIGN", "backed_off"),
        ("ALIGN", "INSERT", "aligned"),
        ("INSERT", "RELEASE", "depth_reached"),
    ]
    assert machine.retries == 1


def test_a_plug_on_the_rim_sweeps_its_yaw_then_searches_again_and_succeeds():
    world = ToyWorld(rim_blocks=1)
    cfg = toy_config()
    machine = make_machine(world, cfg)
    yaws = []
    while machine.phase is not Phase.DONE and world.t_s < 60.0:
        world.step(machine)
        if machine.phase is Phase.ALIGN and machine.stage is AlignStage.YAW:
            x_t = world.rotation.apply([1.0, 0.0, 0.0])
            yaws.append(np.arctan2(x_t[1], x_t[0]) - world.hole.yaw_rad)
    assert machine.phase is Phase.DONE
    assert path(machine)[2:6] == [
        ("SEARCH", "ALIGN", "hole_found"),
        ("ALIGN", "BACKOFF", "not_entered"),
        ("BACKOFF", "APPROACH", "search_again"),
        ("APPROACH", "SEARCH", "surface_contact"),
    ]
    assert path(machine)[-4] == ("ALIGN", "INSERT", "aligned")
    sweep = cfg.insert.yaw_sweep_rad
    assert max(yaws) >= sweep - 0.01 and min(yaws) <= -sweep + 0.01  # both ways, whole
    assert max(np.abs(yaws)) <= sweep + 0.02
    assert machine.retries >= 1


def test_jams_at_one_height_mean_the_rim_whatever_the_depth_by_touch_says():
    # the upright plug stands on the rim sunk 1.5 mm (one end in the opening): the depth by
    # touch reads it entered, and every push jams there
    world = ToyWorld(rim_blocks=1, rim_sink_m=0.0015)
    machine = make_machine(world, toy_config())
    world.run_until(machine, Phase.DONE, max_s=90.0)
    reasons = [r for _, _, r in path(machine)]
    first_jam = reasons.index("jam")
    assert reasons[first_jam : first_jam + 3] == ["jam", "backed_off", "aligned"]
    second_jam = reasons.index("jam", first_jam + 1)
    assert "hole_found" not in reasons[first_jam:second_jam]  # both at the one catch
    # after the second jam at that height the plug no longer counts as entered there: no
    # third push; ALIGN's yaw stage finds it not over the opening, and it searches again
    next_catch = reasons.index("hole_found", second_jam)
    assert reasons[second_jam:next_catch] == [
        "jam",
        "backed_off",
        "not_entered",
        "search_again",
        "surface_contact",
    ]
    assert machine.phase is Phase.DONE


def test_the_walls_holding_the_yaw_end_the_sweep_early_in_the_servo():
    world = ToyWorld(rim_blocks=1, held_yaw_twist=0.01)
    cfg = toy_config()
    machine = make_machine(world, cfg)
    yaws = []
    while not any(t.source is Phase.ALIGN for t in machine.transitions) and world.t_s < 60.0:
        world.step(machine)
        if machine.phase is Phase.ALIGN and machine.stage is AlignStage.YAW:
            x_t = world.rotation.apply([1.0, 0.0, 0.0])
            yaws.append(np.arctan2(x_t[1], x_t[0]) - world.hole.yaw_rad)
    rules = [c.rule for c in world.commands]
    assert "align.yaw_sweep" in rules and "align.twist_held" in rules
    assert rules.index("align.twist_held") > rules.index("align.yaw_sweep")
    assert "align.torque_servo" in rules[rules.index("align.twist_held") :]
    assert max(yaws) - min(yaws) < 0.5 * cfg.insert.yaw_sweep_rad  # the sweep cut short
    # with the rule off the same world sweeps the whole range (as on a bare rim)
    off = replace(cfg, align=replace(cfg.align, twist_sigma=0.0))
    world = ToyWorld(rim_blocks=1, held_yaw_twist=0.01)
    machine = make_machine(world, off)
    world.run_until(machine, Phase.DONE)
    assert "align.twist_held" not in [c.rule for c in world.commands]


def test_align_seeks_the_wall_against_the_lean_then_turns_upright_about_the_heel():
    world = ToyWorld()
    cfg = toy_config()
    machine = make_machine(world, cfg)
    world.run_until(machine, Phase.ALIGN)
    lean = world.rotation.apply([0.0, 0.0, 1.0])[:2]
    start = lowest_edge(world.observe().arm.tcp, machine.plug, world.rotation)
    while machine.stage in (AlignStage.START, AlignStage.SEEK):
        world.step(machine)
    held = lowest_edge(world.observe().arm.tcp, machine.plug, world.rotation)
    moved = held - start
    assert np.dot(moved[:2], lean) < 0.0  # backward, against the lean
    assert np.linalg.norm(moved[:2]) <= cfg.align.seek_max_m
    assert machine.stage is AlignStage.TURN
    while machine.stage is AlignStage.TURN:
        world.step(machine)
    assert tilt_of_rotation(world.rotation) <= cfg.align.tilt_tol_rad
    now = lowest_edge(world.observe().arm.tcp, machine.plug, world.rotation)
    assert np.linalg.norm((now - held)[:2]) < 5e-4  # turned about the heel, held at the wall


def test_a_catch_without_a_wall_is_not_the_opening_and_searches_again():
    world = ToyWorld(catch=0.0)  # the tip drops in, but nothing resists its sideways motion
    cfg = replace(toy_config(), backoff=BackoffSettings(max_retries=1))
    machine = make_machine(world, cfg)
    world.run_until(machine, (Phase.BACKOFF, Phase.INSERT))
    assert ("ALIGN", "BACKOFF", "no_wall") in path(machine)
    world.run_until(machine, Phase.APPROACH)
    assert path(machine)[-1] == ("BACKOFF", "APPROACH", "search_again")


def test_the_force_budget_counts_as_a_jam():
    world = ToyWorld(depth_limit_m=0.002)  # the opening is too shallow for the depth
    cfg = config(backoff=replace(BackoffSettings(), max_retries=1))
    machine = make_machine(world, cfg)
    assert world.run_until(machine, Phase.FAILED) is Phase.FAILED
    assert ("INSERT", "BACKOFF", "jam") in path(machine)
    assert path(machine)[-1] == ("INSERT", "FAILED", "too_many_retries")


def test_too_many_jams_fail_with_too_many_retries():
    world = ToyWorld(jam_depth_m=0.002, jams=100)
    machine = make_machine(world, config(backoff=replace(BackoffSettings(), max_retries=1)))
    assert world.run_until(machine, Phase.FAILED) is Phase.FAILED
    reasons = [r for _, _, r in path(machine)]
    assert reasons.count("jam") == 1  # the second: no retry left
    assert path(machine)[-1] == ("INSERT", "FAILED", "too_many_retries")


def _yaw_from_approach(machine, world) -> float:
    """The TCP's turn about B's z from the approach rotation (rad)."""
    turn = world.rotation * machine._approach_rot.inv()
    return float(turn.as_rotvec()[2])


def test_a_search_out_of_time_searches_again_with_each_pass_at_another_yaw():
    world = ToyWorld(hole_offset_m=(0.02, 0.0))  # outside the searched square
    search = replace(SearchSettings(), uncertainty_xy_m=0.001)  # a short pattern
    cfg = config(
        search=search,
        timeouts=replace(Timeouts(), search_s=6.0),
        backoff=replace(BackoffSettings(), max_retries=2),
    )
    machine = make_machine(world, cfg)
    length_s = SearchPattern("spiral", search.pitch_m, 0.001).length_m / search.speed_m_s
    assert 1.5 < length_s < 2.5  # so each SEARCH after the first runs two passes and more
    yaws = []  # (SEARCH's path length since its first timeout, m; yaw, rad) while dragging
    while machine.phase is not Phase.FAILED and world.t_s < 60.0:
        world.step(machine)
        if machine.phase is Phase.SEARCH and machine.memory.yaw_passes_from_m is None:
            assert abs(_yaw_from_approach(machine, world)) < 1e-3  # the nominal yaw
        elif machine.phase is Phase.SEARCH:
            yaws.append(
                (
                    machine.memory.search_s_m - machine.memory.yaw_passes_from_m,
                    _yaw_from_approach(machine, world),
                )
            )
    reasons = [r for _, _, r in path(machine)]
    assert reasons.count("search_timeout") == 2  # each a retry, not a failure
    assert path(machine)[-1] == ("SEARCH", "FAILED", "too_many_retries")
    length_m = length_s * search.speed_m_s
    step = search.retry_yaw_rad
    for k, expected in enumerate((step, -step, 0.0, step)):
        # the yaw of the pass's second half: the servo has turned the plug by then
        held = [y for s, y in yaws if (k + 0.5) * length_m < s < (k + 1) * length_m]
        assert held, f"pass {k} not searched"
        assert np.allclose(held, expected, atol=0.003), (k, min(held), max(held))


def test_a_search_without_a_pattern_retries_at_the_nominal_yaw():
    # no positional uncertainty: no pattern to pass along, so no yawed passes either
    world = ToyWorld(hole_offset_m=(0.02, 0.0))
    cfg = config(
        search=replace(SearchSettings(), uncertainty_xy_m=0.0),
        timeouts=replace(Timeouts(), search_s=2.0),
        backoff=replace(BackoffSettings(), max_retries=1),
    )
    machine = make_machine(world, cfg)
    while machine.phase is not Phase.FAILED and world.t_s < 30.0:
        world.step(machine)
        if machine.phase is Phase.SEARCH:
            assert abs(_yaw_from_approach(machine, world)) < 1e-3
    assert [r for _, _, r in path(machine)].count("search_timeout") == 1
    assert path(machine)[-1] == ("SEARCH", "FAILED", "too_many_retries")


def test_an_align_timeout_lifts_clear_of_the_surface_then_searches_again():
    world = ToyWorld()
    cfg = config(
        timeouts=replace(Timeouts(), align_s=0.3),  # too short for any alignment
        backoff=replace(BackoffSettings(), max_retries=1),
    )
    machine = make_machine(world, cfg)
    world.run_until(machine, Phase.BACKOFF)
    assert path(machine)[-1] == ("ALIGN", "BACKOFF", "align_timeout")
    caught = world.observe()
    caught_depth = machine.touch.depth(caught.arm.tcp, world.rotation)
    assert caught_depth > 0.0  # the tip's edge in the opening
    world.run_until(machine, Phase.APPROACH)
    assert path(machine)[-1] == ("BACKOFF", "APPROACH", "search_again")
    lifted = world.observe()
    # lifted clear: the lowest edge the back-off distance above the surface found, which
    # is more than the back-off distance for a tip that was below the surface
    assert -machine.touch.depth(lifted.arm.tcp, world.rotation) >= cfg.backoff.distance_m
    lift_m = lifted.arm.tcp.xyz_m[2] - caught.arm.tcp.xyz_m[2]
    assert lift_m > cfg.backoff.distance_m + 0.5 * caught_depth
    assert world.run_until(machine, Phase.FAILED) is Phase.FAILED  # the next one: no retry left
    assert path(machine)[-1] == ("ALIGN", "FAILED", "too_many_retries")


@pytest.mark.parametrize("pattern", ["spiral", "raster"])
def test_friction_alone_never_reads_as_the_hole_over_a_whole_pattern(pattern):
    world = ToyWorld(hole_offset_m=(0.02, 0.0), seed=5)
    search = replace(SearchSettings(), pattern=pattern)
    cfg = config(search=search, timeouts=replace(Timeouts(), search_s=24.0))
    machine = make_machine(world, cfg)
    world.run_until(machine, Phase.BACKOFF, max_s=60.0)
    assert path(machine)[-1] == ("SEARCH", "BACKOFF", "search_timeout")
    searched_s = machine.transitions[-1].t_s - machine.transitions[-2].t_s
    assert searched_s == pytest.approx(24.0, abs=0.02)
    covered = SearchPattern(pattern, search.pitch_m, search.uncertainty_xy_m).length_m
    assert 24.0 * search.speed_m_s > covered  # the whole pattern was dragged


def test_total_timeout():
    world = ToyWorld()
    machine = make_machine(world, config(timeouts=replace(Timeouts(), total_s=1.5)))
    world.run_until(machine, Phase.FAILED)
    assert path(machine)[-1] == ("APPROACH", "FAILED", "timeout")


def test_grasp_timeout_when_the_gripper_never_holds():
    world = ToyWorld()
    cfg = config(gripper=replace(GripperSettings(), close_width_m=0.01))  # wider than the plug
    machine = make_machine(world, cfg)
    world.run_until(machine, Phase.FAILED)
    assert path(machine) == [("GRASP", "FAILED", "timeout")]


def test_limit_exceeded_without_a_board_overtravel():
    world = ToyWorld(board=False)
    machine = make_machine(world)
    world.run_until(machine, Phase.FAILED)
    assert path(machine)[-1] == ("APPROACH", "FAILED", "limit_exceeded")
    overtravel = MachineConfig().approach.overtravel_m
    assert world.tip[2] == pytest.approx(world.hole.z_m - overtravel, abs=1e-4)


def test_limit_exceeded_on_the_force_limit():
    world = ToyWorld()
    cfg = config(
        limits=replace(toy_config().limits, force_limit=0.05),
        insert=replace(toy_config().insert, force_budget=0.04),
    )
    machine = make_machine(world, cfg)
    world.run_until(machine, Phase.FAILED)
    assert path(machine)[-1] == ("SEARCH", "FAILED", "limit_exceeded")


def test_limit_exceeded_on_the_tilt_torque_limit():
    world = ToyWorld(jam_depth_m=0.002, jams=1, jam_torque=0.2)
    machine = make_machine(world)
    world.run_until(machine, Phase.FAILED)
    assert path(machine)[-1][1:] == ("FAILED", "limit_exceeded")
    assert path(machine)[-1][0] in ("INSERT", "BACKOFF", "ALIGN")


def test_losing_contact_in_search_probes_down_and_finds_the_opening_below():
    world = ToyWorld(hole_offset_m=(0.02, 0.0))
    cfg = config(search=replace(SearchSettings(), hole_drop_ratio=0.0))
    machine = make_machine(world, cfg)
    world.run_until(machine, Phase.SEARCH)
    for _ in range(60):
        world.step(machine)
    world.floor_drop_m = 0.002  # the tip fell into a deep opening: support 2 mm lower
    first = len(world.commands)
    assert world.run_until(machine, Phase.ALIGN) is Phase.ALIGN
    assert path(machine)[-1] == ("SEARCH", "ALIGN", "hole_found")
    decided = [(c.stage, c.rule) for c in world.commands[first:]]
    assert ("search.drag", "search.lost_contact") in decided  # the tick that began the probe
    assert decided[-1] == ("search.probe", "search.hole_found:probe")
    assert world.tip[2] < world.hole.z_m - cfg.search.in_hole_depth_m


def test_losing_contact_then_touching_the_surface_again_drags_on():
    world = ToyWorld(hole_offset_m=(0.02, 0.0))
    # the toy's rigid tip sinks into its board by about 0.5 mm while probing: count contact
    # down to 2 mm as the surface
    search = replace(SearchSettings(), hole_drop_ratio=0.0, in_hole_depth_m=0.002)
    cfg = config(search=search, timeouts=replace(Timeouts(), search_s=6.0))
    machine = make_machine(world, cfg)
    world.run_until(machine, Phase.SEARCH)
    world.board = False  # contact lost ...
    while machine.phase is Phase.SEARCH and machine.stage is not SearchStage.PROBE:
        world.step(machine)
    world.board = True  # ... and found again on the surface while probing down
    while machine.phase is Phase.SEARCH and machine.stage is SearchStage.PROBE:
        world.step(machine)
    assert machine.phase is Phase.SEARCH and machine.stage is SearchStage.DRAG
    world.run_until(machine, Phase.BACKOFF)
    assert path(machine)[-1] == ("SEARCH", "BACKOFF", "search_timeout")  # it searched on


def test_contact_lost_during_search():
    world = ToyWorld(hole_offset_m=(0.02, 0.0))
    # the load-drop rule would read the vanished board as the opening
    machine = make_machine(world, config(search=replace(SearchSettings(), hole_drop_ratio=0.0)))
    world.run_until(machine, Phase.SEARCH)
    for _ in range(60):
        world.step(machine)
    assert machine.phase is Phase.SEARCH
    world.board = False
    world.run_until(machine, Phase.FAILED)
    assert path(machine)[-1] == ("SEARCH", "FAILED", "contact_lost")


def test_slip_with_the_fail_policy():
    world = ToyWorld()
    machine = make_machine(world, config(slip=replace(SlipSettings(), policy="fail")))
    world.run_until(machine, Phase.SEARCH)
    world.slip_gross = True
    world.run_until(machine, Phase.FAILED, max_s=world.t_s + 0.1)
    assert path(machine)[-1] == ("SEARCH", "FAILED", "slip")


def test_a_lost_grasp_is_a_slip():
    world = ToyWorld()
    machine = make_machine(world, config(slip=replace(SlipSettings(), policy="fail")))
    world.run_until(machine, Phase.APPROACH)
    world.step(machine)
    world.drop_plug = True
    world.step(machine)
    assert path(machine)[-1] == ("APPROACH", "FAILED", "slip")


@pytest.mark.parametrize(("trigger", "slips"), [("gross", False), ("suspected", True)])
def test_the_slip_trigger_decides_whether_incipient_slip_counts(trigger, slips):
    world = ToyWorld()
    cfg = config(slip=replace(SlipSettings(), policy="fail", trigger=trigger))
    machine = make_machine(world, cfg)
    world.run_until(machine, Phase.SEARCH)
    world.slip_suspected = True
    for _ in range(10):
        world.step(machine)
    assert (machine.phase is Phase.FAILED) is slips


def test_slip_with_the_regrasp_policy_regrasps_rezeroes_and_succeeds():
    world = ToyWorld()
    machine = make_machine(world)
    world.run_until(machine, Phase.SEARCH)
    world.slip_gross = True
    world.run_until(machine, Phase.GRASP, max_s=world.t_s + 0.1)
    world.slip_gross = False
    lifted_from = world.p[2]
    assert world.run_until(machine, Phase.DONE) is Phase.DONE
    assert ("SEARCH", "GRASP", "slip_regrasp") in path(machine)
    assert path(machine)[-7:] == HAPPY
    assert machine.retries == 1
    assert world.rezero_count == 2
    widths = [c.gripper.width_m for c in world.commands if c.gripper is not None]
    # widths[0:2]: the first grasp's pre-close and close
    assert widths[2] == pytest.approx(world.plug.thickness_m + 0.0005)  # opened a little
    assert widths[3] == 0.0  # and closed again (no pre-close: already near the plug)
    assert max(c.twist.linear_m_s[2] for c in world.commands) > 0  # lifted first
    assert lifted_from < world.hole.z_m + 0.02


def test_slip_regrasp_beyond_the_retries_fails():
    world = ToyWorld()
    machine = make_machine(world, config(backoff=replace(BackoffSettings(), max_retries=0)))
    world.run_until(machine, Phase.SEARCH)
    world.slip_gross = True
    world.run_until(machine, Phase.FAILED, max_s=world.t_s + 0.1)
    assert path(machine)[-1] == ("SEARCH", "FAILED", "too_many_retries")


@pytest.mark.parametrize(
    ("phase", "source"),
    [
        (Phase.GRASP, "loop"),
        (Phase.APPROACH, "gripper"),
        (Phase.SEARCH, "arm"),
        (Phase.ALIGN, "loop"),
        (Phase.INSERT, "gripper"),
        (Phase.RETRACT, "arm"),
    ],
)
def test_a_device_fault_fails_from_any_phase(phase, source):
    world = ToyWorld()
    machine = make_machine(world)
    assert world.run_until(machine, phase) is phase
    if source == "loop":
        world.fault = "tactile frame stale"
    elif source == "arm":
        world.arm_error = 31
    else:
        world.gripper_fault = 7
    command = world.step(machine)
    assert path(machine)[-1] == (phase.name, "FAILED", "device_fault")
    assert command.twist == type(command.twist)() and command.gripper is None


def test_a_terminal_phase_stays_and_holds_still():
    world = ToyWorld(board=False)
    machine = make_machine(world)
    world.run_until(machine, Phase.FAILED)
    count = len(machine.transitions)
    world.teleop = replace(world.teleop, in_control=True, estop=True)
    for _ in range(5):
        command = world.step(machine)
        assert command.twist == type(command.twist)()
    assert len(machine.transitions) == count and machine.phase is Phase.FAILED
