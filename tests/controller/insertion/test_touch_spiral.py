"""The touch spiral: the blind baseline's search with the force read by touch (the tactile
estimate's axial force, ``TactileAxialForce``), in the toy world with the arm's F/T sensor
off: it needs the tactile force to touch, catch and push; a single frame's outlier is no
catch; a probe rewinds the pattern to where the tip was when the frame was captured."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from controller.insertion.force_reading import ArmForce, TactileAxialForce
from controller.insertion.imprint import FaceOffset
from controller.insertion.interface import Observation, Phase
from controller.insertion.machine_config import GripperSettings, s2t_matrix
from controller.insertion.motion import tip_position
from controller.insertion.spiral import SpiralMachine, TouchSpiralConfig
from controller.insertion.spiral.spiral_feel import (
    RockSettings,
    flat_angle,
    flat_candidate,
    sweep_step,
)
from controller.insertion.spiral.spiral_search import SearchStage
from controller.insertion.spiral.torque_servo import TorqueServo, TorqueServoSettings
from controller.run.controllers import CONTROLLERS
from controller.run.task import load_task
from core.config import ConfigError
from tests.controller.insertion.test_blind import reasons
from tests.controller.insertion.world import ToyWorld, estimate

SHARE = 0.5
SPIRAL = TouchSpiralConfig(GripperSettings(), pitch_m=0.0005, half_width_m=0.002,
                           touch_force_n=1.0, press_force_n=2.0, stop_force_n=6.0,
                           sweep_speed_m_s=0.01, descend_speed_m_s=0.005, yaw_step_rad=0.02,
                           yaw_range_rad=0.02, timeout_s=60.0, force_window=3,
                           axial_weights=(0.0, 0.0, 0.0, 0.0, 1 / SHARE, 0.0, 0.0, 0.0, 0.0),
                           rewind=True)  # fmt: skip


def run(world: ToyWorld, machine: SpiralMachine, max_s: float = 80.0) -> None:
    """Step to a terminal phase (or ``max_s``)."""
    while world.t_s < max_s and machine.phase not in (Phase.DONE, Phase.FAILED):
        world.step(machine)


def touch_world(**kwargs) -> ToyWorld:
    """The toy world without the arm's force; the tactile axial force is the finger's share
    of the board's push, with the estimate's noise (0.3 mN)."""
    return ToyWorld(arm_force=False, axial_share=SHARE, open_gel_zeroes=True, **kwargs)


def spiral(world: ToyWorld, config: TouchSpiralConfig = SPIRAL) -> SpiralMachine:
    reading = TactileAxialForce(config.axial_weights, config.force_window)
    return SpiralMachine(config, world.plug, world.hole, reading)


def test_by_touch_alone_it_catches_pushes_to_the_floor_and_releases():
    world = touch_world()
    machine = spiral(world)
    run(world, machine)
    assert reasons(machine) == [
        "grasped", "above_the_opening", "caught", "bottomed", "released", "retracted",
    ]  # fmt: skip
    # the open gel taken before the close, the reference after it
    first_capture = next(i for i, c in enumerate(world.commands) if c.capture_open_tactile)
    close = next(
        i for i, c in enumerate(world.commands)
        if c.gripper is not None and c.gripper.width_m == SPIRAL.gripper.close_width_m
    )  # fmt: skip
    assert first_capture < close and world.rezero_count == 1


def test_without_the_tactile_force_it_never_touches_and_inserts_nothing():
    world = touch_world()
    world.axial_share = 0.0  # the estimate's force is noise only
    machine = spiral(world)
    run(world, machine, max_s=40.0)
    assert "caught" not in reasons(machine)
    rules = {c.rule for c in world.commands}
    assert "search.sweep" not in rules  # the board is never felt: the descent goes on


def test_a_single_frames_outlier_is_no_catch():
    reading = TactileAxialForce(SPIRAL.axial_weights, window=3)
    forces = [2.0, 2.0, 0.0, 2.0, 2.0]  # N on the plug; the third frame drops out
    read = []
    for k, force in enumerate(forces):
        obs = observation(t_s=0.04 * k, shear_y=force * SHARE)
        read.append(reading.read(obs))
    assert all(value == pytest.approx(2.0) for value, _ in read[1:])
    # the median's time is the middle frame's
    assert read[-1][1] == pytest.approx(0.04 * 3)


def test_zeroing_frames_give_no_force_and_start_the_window_again():
    reading = TactileAxialForce(SPIRAL.axial_weights, window=3)
    assert reading.read(observation(0.0, shear_y=1.0)) == (pytest.approx(2.0), 0.0)
    zeroing = replace(observation(0.04, shear_y=0.0), wrench=estimate(0.04, zeroing=True))
    assert reading.read(zeroing) is None
    assert reading.read(observation(0.08, shear_y=0.25)) == (pytest.approx(0.5), 0.08)


def test_the_arm_force_is_the_window_mean_at_its_mean_time():
    reading = ArmForce(window=2)
    world = ToyWorld(force_bias_n=1.0)
    first = reading.read(world.observe())
    world.t_s += 0.01
    world.force_bias_n = 3.0
    second = reading.read(world.observe())
    assert first == (pytest.approx(1.0), pytest.approx(0.0))
    assert second == (pytest.approx(2.0), pytest.approx(0.005))


def test_a_probe_rewinds_the_pattern_to_the_frames_capture_time():
    world = touch_world(frame_every=4)  # slow frames: the reading lags the tip by more
    machine = spiral(world)
    while machine.phase is not Phase.INSERT and world.t_s < 40.0:
        before = (machine.stage, machine.memory.s_m)
        world.step(machine)
        if before[0] is SearchStage.SWEEP and machine.stage is SearchStage.PROBE:
            assert machine.memory.s_m < before[1]  # back along the pattern
            assert machine.memory.s_m == pytest.approx(machine.memory.s_at(machine.force_t_s))
            break
    else:
        pytest.fail("no probe")


def test_without_rewind_a_probe_holds_the_swept_length():
    world = touch_world(frame_every=4)
    machine = spiral(world, replace(SPIRAL, rewind=False))
    while world.t_s < 40.0:
        before = (machine.stage, machine.memory.s_m)
        world.step(machine)
        if before[0] is SearchStage.SWEEP and machine.stage is SearchStage.PROBE:
            assert machine.memory.s_m == before[1]
            break
    else:
        pytest.fail("no probe")


def test_the_product_and_its_ablations_read_the_tasks_touch_spiral_section():
    config = load_task("usb_c", ["touch_spiral.force_window=4"]).config
    for name in ("dipole", "fingervision", "zero_torque", "torque_only"):
        machine = CONTROLLERS[name].machine(config)
        assert isinstance(machine, SpiralMachine)
        assert machine.config is config.touch_spiral
        assert isinstance(machine.reading, TactileAxialForce)
        assert not CONTROLLERS[name].arm_force  # no F/T sensor


def observation(t_s: float, shear_y: float) -> Observation:
    world = ToyWorld()
    obs = world.observe()
    return replace(obs, t_s=t_s, wrench=estimate(t_s, shear_y=shear_y))


def test_the_weights_read_every_term_and_the_torques_magnitudes():
    weights = (1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0)
    reading = TactileAxialForce(weights, window=1)
    obs = observation(0.0, shear_y=0.5)
    wrench = estimate(0.0, tau_x=-0.1, tau_y=0.2, tau_z=-0.3, shear_x=0.4, shear_y=0.5, normal=0.6)
    force, _ = reading.read(replace(obs, wrench=wrench))
    terms = (-0.1, 0.2, -0.3, 0.4, 0.5, 0.6, 0.1, 0.2, 0.3)
    assert force == pytest.approx(sum(w * t for w, t in zip(weights, terms, strict=True)))


@pytest.mark.parametrize(
    ("weights", "message"),
    [
        ("[1.0, 2.0]", r"key 'touch_spiral.axial_weights': expected 9 items"),
        ("[1, 2, 3, 4, 5, 6, 7, 8, .nan]", r"key 'touch_spiral.axial_weights\[8\]': expected"),
    ],
)
def test_axial_weights_other_than_nine_finite_numbers_are_refused(weights, message):
    with pytest.raises(ConfigError, match=message):
        load_task("usb_c", [f"touch_spiral.axial_weights={weights}"])


def test_with_the_torque_servo_it_pushes_turning_about_the_tip_and_still_inserts():
    world = touch_world()
    config = replace(SPIRAL, push_servo=TorqueServoSettings((20.0, 20.0, 20.0)))
    reading = TactileAxialForce(config.axial_weights, config.force_window)
    machine = SpiralMachine(config, world.plug, world.hole, reading, TorqueServo(config.push_servo))
    run(world, machine)
    assert reasons(machine) == [
        "grasped", "above_the_opening", "caught", "bottomed", "released", "retracted",
    ]  # fmt: skip
    pushes = [c for c in world.commands if c.rule == "insert.servo_push"]
    assert pushes and all(c.stage == "insert.push" for c in pushes)
    assert not any(c.rule == "insert.push" for c in world.commands)


@pytest.mark.parametrize(("source", "credited"), [("tip", True), ("tcp", False)])
def test_the_probe_credits_the_wrists_extension_only_when_asked(source, credited):
    world = touch_world()
    machine = spiral(world, replace(SPIRAL, catch_drop_from=source))
    obs = world.observe()
    machine.memory.press_z_m = obs.arm.tcp.xyz_m[2] + 0.0002  # the TCP 0.2 mm below the press
    low = 0.5  # N, a reading 1.5 N under the press: the wrist extended by 1.5 mm, if true
    expected = 0.0002 + (SPIRAL.press_force_n - low) / SPIRAL.wrist_z_stiffness_n_m
    drop = machine.catch_drop_m(obs, low)
    assert drop == pytest.approx(expected if credited else 0.0002)
    # above the press both count the wrist's compression against the drop
    high = SPIRAL.press_force_n + 1.0
    assert machine.catch_drop_m(obs, high) == pytest.approx(0.0002 - 1.0 / 1000.0)


ROCK = RockSettings(enabled=True)
TILTED = dict(thickness_tilt_rad=0.07, thickness_tol_rad=0.02)  # 4 deg: the slot takes 1.1


def rocking(world: ToyWorld, rock: RockSettings | None = ROCK) -> SpiralMachine:
    reading = TactileAxialForce(SPIRAL.axial_weights, SPIRAL.force_window, world.s2t)
    return SpiralMachine(SPIRAL, world.plug, world.hole, reading, rock=rock)


def test_feel_finds_the_thickness_tilt_and_the_plug_upright_goes_in():
    world = touch_world(**TILTED)
    machine = rocking(world)
    run(world, machine)
    assert reasons(machine) == [
        "grasped", "above_the_opening", "touched", "felt", "caught", "bottomed", "released",
        "retracted",
    ]  # fmt: skip
    assert machine.tilt_x_estimate_rad == pytest.approx(0.07, abs=0.01)
    rules = {c.rule for c in world.commands}
    assert {"feel.rock", "feel.rock_back", "feel.turn"} <= rules


def test_feel_publishes_its_estimate_and_the_tip_offset_it_implies():
    world = touch_world(**TILTED)
    machine = rocking(world)
    run(world, machine)
    (estimate,) = machine.in_hand_estimates
    tilt = machine.tilt_x_estimate_rad
    assert tilt is not None
    assert (estimate.plane, estimate.method, estimate.kept) == ("thickness", "rock", True)
    assert estimate.tilt_rad == tilt
    # the tip turned by the tilt about T x: the plug's length times its sine, along T y
    length = world.plug.length_m
    assert estimate.tip_offset_m == pytest.approx(length * math.sin(tilt), rel=1e-12)
    assert machine.tip_y_estimate_m == estimate.tip_offset_m
    assert machine.tip_y_estimate_m == pytest.approx(length * math.sin(0.07), abs=length * 0.01)
    # made in FEEL, when its rock back ended (before the turn)
    touched, felt = (t.t_s for t in machine.transitions if t.reason in ("touched", "felt"))
    assert touched < estimate.t_s < felt


def test_without_feel_the_tilted_plug_is_never_caught():
    world = touch_world(**TILTED)
    machine = rocking(world, rock=None)
    run(world, machine)
    assert "caught" not in reasons(machine) and "touched" not in reasons(machine)
    assert machine.tilt_x_estimate_rad is None


def test_without_a_step_in_the_torque_feel_keeps_the_plug_as_it_was():
    world = touch_world(thickness_tilt_rad=0.07, thickness_edge_m=0.0)  # no lever: no step
    machine = rocking(world)
    run(world, machine)
    assert reasons(machine)[2:4] == ["touched", "no_flat_face"]
    assert machine.tilt_x_estimate_rad is None and machine.tcp_turn_rad == [0.0, 0.0]
    # the two pairs of legs' angles are published, neither kept; no tip offset recorded
    assert [e.kept for e in machine.in_hand_estimates] == [False, False]
    assert machine.tip_y_estimate_m is None


def test_the_flat_angle_is_the_two_sweeps_steps_mean_and_needs_both():
    up = [(a * 0.01, 0.001 if a < 5 else 0.004) for a in range(10)]  # steps at 0.045 rad
    down = [(0.09 - a * 0.01, 0.004 if a < 6 else 0.001) for a in range(10)]  # at 0.035
    assert sweep_step(up, 3) == pytest.approx((0.045, 0.003))
    assert flat_angle([up, down], ROCK) == pytest.approx(0.04)
    flat = [(a * 0.01, 0.001) for a in range(10)]
    assert flat_angle([up, flat], ROCK) is None  # one sweep without a step
    far = [(a - 0.1, t) for a, t in down]
    assert flat_angle([up, far], ROCK) is None  # the sweeps disagree
    assert sweep_step(up[:5], 3) is None  # too few frames
    # the candidate, kept or not: the same mean, the checks' verdict beside it
    assert flat_candidate([up, down], ROCK) == (flat_angle([up, down], ROCK), True)
    assert flat_candidate([up, far], ROCK) == pytest.approx((0.04 - 0.05, False))
    assert flat_candidate([up, flat], ROCK)[1] is False
    assert flat_candidate([up, down[:5]], ROCK) is None


def test_a_flat_angle_the_other_side_of_upright_is_found_on_a_third_leg():
    world = touch_world(thickness_tilt_rad=-0.07, thickness_tol_rad=0.02)
    machine = rocking(world)
    run(world, machine)
    assert "felt" in reasons(machine) and "bottomed" in reasons(machine)
    assert machine.tilt_x_estimate_rad == pytest.approx(-0.07, abs=0.01)
    assert "feel.rock_again" in {c.rule for c in world.commands}
    # the first two legs' angle published but not kept, then the kept one
    assert [e.kept for e in machine.in_hand_estimates] == [False, True]
    assert machine.in_hand_estimates[-1].tilt_rad == machine.tilt_x_estimate_rad


def test_feel_waits_for_its_pass():
    world = touch_world(**TILTED)
    machine = rocking(world, rock=replace(ROCK, at_pass=1))
    run(world, machine)
    first_feel = next(i for i, c in enumerate(world.commands) if c.rule.startswith("feel."))
    first_sweep = next(i for i, c in enumerate(world.commands) if c.rule == "search.sweep")
    assert first_sweep < first_feel
    assert "felt" in reasons(machine) and "bottomed" in reasons(machine)


def test_the_tip_is_taken_along_the_plug_turned_by_the_grasps_tilt():
    world = touch_world(thickness_tilt_rad=0.07)
    machine = rocking(world)
    world.rotation = world.rotation * Rotation.from_euler("xz", [0.05, 0.3])  # any pose
    obs = world.observe()
    nominal = machine.tip_b(obs)  # before FEEL: the tip along T z
    assert nominal == pytest.approx(tip_position(obs.arm.tcp, world.plug.length_m))
    machine.grasp_turn_rad[0] = world.thickness_tilt_rad  # FEEL's estimate, exact
    assert machine.tip_b(obs) == pytest.approx(world.tip, abs=1e-9)
    assert machine.tip_xy(obs) == pytest.approx(world.tip[:2], abs=1e-9)
    shift = world.plug.length_m * math.sin(0.07)
    assert np.linalg.norm(nominal - world.tip) == pytest.approx(shift, rel=0.05)


def test_after_feel_the_pattern_is_centred_on_the_tip_itself():
    world = touch_world(**TILTED)
    machine = rocking(world)
    world.run_until(machine, Phase.FEEL)
    assert machine.grasp_turn_rad == [0.0, 0.0]  # the rock turns about the nominal tip
    world.run_until(machine, Phase.SEARCH)
    estimate_rad = machine.tilt_x_estimate_rad
    assert estimate_rad is not None and machine.grasp_turn_rad[0] == estimate_rad
    for _ in range(30):  # the TCP's move to the tip's own place, pressed
        world.step(machine)
    shift_m = world.plug.length_m * math.sin(world.thickness_tilt_rad)  # the nominal's miss
    while machine.phase is Phase.SEARCH:
        target = machine.tip_target(machine.memory.s_m, 0.0)[:2]
        assert np.linalg.norm(world.tip[:2] - target) < 0.3 * shift_m
        world.step(machine)


def test_feel_at_its_site_rocks_on_the_board_clear_of_the_opening_then_searches():
    world = touch_world(**TILTED)
    machine = rocking(world, rock=replace(ROCK, site_m=0.01))
    opening = np.append(world.hole_xy, world.hole.z_m)
    world.run_until(machine, Phase.FEEL)
    site = machine.tip_target(0.0, 0.0)  # FEEL's site: 10 mm along the opening's y
    assert site[:2] - [world.hole.x_m, world.hole.y_m] == pytest.approx([0.0, 0.01])
    tips = []
    while machine.phase is Phase.FEEL:
        world.step(machine)
        tips.append(world.tip.copy())
    pressed = [tip for tip in tips if tip[2] <= world.hole.z_m + 0.0005]
    assert pressed and all(np.linalg.norm(tip[:2] - opening[:2]) > 0.008 for tip in pressed)
    assert all(np.linalg.norm(tip[:2] - site[:2]) < 0.001 for tip in pressed)
    # FEEL ends in the air above its site; SEARCH starts its pass again from its start
    assert tips[-1][2] >= world.hole.z_m + 0.5 * SPIRAL.hover_m
    assert not machine.at_feel_site
    run(world, machine)
    assert reasons(machine)[2:5] == ["touched", "felt", "caught"]
    assert machine.tilt_x_estimate_rad == pytest.approx(0.07, abs=0.01)
    assert "feel.lift" in {c.rule for c in world.commands}
    assert "bottomed" in reasons(machine)


def test_feel_in_the_width_plane_finds_the_tilt_about_t_y_and_places_the_tip_by_both():
    world = touch_world(grasp_tilt_rad=0.05, **TILTED)  # the tip toward +T x and +T y
    machine = rocking(world, rock=replace(ROCK, site_m=0.01, width=True))
    world.run_until(machine, Phase.SEARCH, max_s=10.0)
    world.run_until(machine, Phase.FEEL)
    while machine.phase is Phase.FEEL:
        world.step(machine)
    # the TCP's flat turn about T y is -0.05: the first leg (toward +) misses it, the third finds it
    assert [(e.plane, e.kept) for e in machine.in_hand_estimates] == [
        ("thickness", True), ("width", False), ("width", True)
    ]  # fmt: skip
    assert machine.tilt_x_estimate_rad == pytest.approx(0.07, abs=0.01)
    assert machine.grasp is not None and machine.grasp.tilt_rad == pytest.approx(0.05, abs=0.01)
    width = machine.in_hand_estimates[-1]
    assert width.tilt_rad == machine.grasp.tilt_rad
    assert width.tip_offset_m == pytest.approx(world.plug.length_m * math.sin(width.tilt_rad))
    # the tip placed by both tilts; the TCP turned upright in the thickness plane only
    assert machine.tip_b(world.observe()) == pytest.approx(world.tip, abs=0.0003)
    assert machine.tcp_turn_rad == [machine.tilt_x_estimate_rad, 0.0]
    # the plug's axis from the TCP's untilted pose: upright about T x, still tilted about T y
    axis = machine._untilted().inv().apply(world.rotation.apply(world._axis_t()))
    assert axis == pytest.approx([math.sin(0.05), 0.0, math.cos(0.05)], abs=0.01)
    rules = {c.rule for c in world.commands}
    assert {"feel.width_rock", "feel.width_rock_back", "feel.width_rock_again"} <= rules
    run(world, machine)
    assert "bottomed" in reasons(machine)


def test_without_the_width_rock_the_width_plane_is_not_estimated():
    world = touch_world(grasp_tilt_rad=0.05, **TILTED)
    machine = rocking(world, rock=replace(ROCK, site_m=0.01))
    run(world, machine)
    assert machine.grasp is None and machine.tcp_turn_rad[1] == 0.0
    assert [e.plane for e in machine.in_hand_estimates] == ["thickness"]
    assert not {c.rule for c in world.commands} & {"feel.width_rock", "feel.width_turn"}


@pytest.mark.parametrize("task", ["usb_c", "usb_a"])
def test_the_shipped_passes_yaw_out_to_the_openings_yaw_uncertainty(task):
    """Every yaw the scene draws for the opening lies within half a step of a pass's yaw: a
    floored step count once left the last passes at +-2 deg of a +-3 deg uncertainty."""
    loaded = load_task(task, (), with_calibration=False)
    spiral, edge = loaded.config.touch_spiral, loaded.scene.hole_uncertainty.yaw_rad
    offsets = np.array(spiral.yaw_offsets)
    drawn = np.linspace(-edge, edge, 601)
    gap = np.abs(drawn[:, None] - offsets[None, :]).min(axis=1).max()
    assert gap <= spiral.yaw_step_rad / 2 + 1e-4


def test_the_imprint_puts_the_tip_across_by_the_plugs_offset_in_the_fingers():
    world = touch_world()
    reading = TactileAxialForce(SPIRAL.axial_weights, SPIRAL.force_window)
    face = FaceOffset(0.5, s2t_matrix(("+x", "+z", "-y")))
    machine = SpiralMachine(SPIRAL, world.plug, world.hole, reading, face=face)
    plain = spiral(world)
    obs = world.observe()
    for m in (machine, plain):
        m.step(obs)
    assert machine.face_offset_m is None and machine.tip_x_estimate_m is None
    machine.step(replace(obs, t_s=obs.t_s + 0.01, contact_centre_s_m=(-0.0004, 0.003)))
    assert machine.face_offset_m == pytest.approx(-0.0008)  # the centre over the gain
    assert machine.tip_t()[0] == pytest.approx(-0.0008)
    assert machine.tip_t()[2] == pytest.approx(world.plug.length_m)
    assert machine.tip_x_estimate_m is None  # FEEL's width-plane tilt not yet found
    machine.set_rock_estimate(1, -0.05)  # the TCP's turn: the tip toward +T x
    assert machine.tip_x_estimate_m == pytest.approx(-0.0008 + world.plug.length_m * math.sin(0.05))
    (published,) = machine.in_hand_estimates
    assert published.method == "imprint" and published.tip_offset_m == pytest.approx(-0.0008)
    assert plain.tip_t()[0] == 0.0 and plain.tip_x_estimate_m is None
    unused = FaceOffset(0.0, np.eye(3))
    assert unused.read(replace(obs, contact_centre_s_m=(0.001, 0.0))) is None


def test_the_product_reads_the_imprint_with_its_tasks_gain():
    config = load_task("usb_c", ["touch_spiral.imprint_gain=0.4"]).config
    machine = CONTROLLERS["dipole"].machine(config)
    assert machine.face is not None and machine.face.gain == 0.4
    off = CONTROLLERS["dipole"].machine(load_task("usb_c", ["touch_spiral.imprint_gain=0"]).config)
    assert off.face is None
