"""Building the simulated insertion: the world, its clock, the twins the controller drives,
and the ground truth it never sees.

``build_insertion_sim(scene, plug, hole_nominal, devices, seed)`` draws the true hole, the
board's height and tilt and the plug's pose in the grasp (``draws.draw_scene``, seeded by
``seed``), builds the physics, and the
twins on one ``SceneClock`` (``ManualClock`` base: as fast as possible; ``realtime``:
``MonotonicClock`` from 0, or with ``paced`` a ``PacedClock``, which waits for the
controller on a busy machine):

* the SimArm, its configuration adapted to the scene through the config objects: it
  starts upright over the nominal hole, the plug's tip ``start_above_hole_m`` above the
  board, turned to the nominal yaw (or, with ``start_depth_m``, partly inserted in the
  true hole, aligned with it: the teleoperated alignment demo's start); its envelope is
  the robot configuration's, unchanged
  (a task whose insertion that envelope cannot reach is refused when it loads:
  ``core.envelope_checks``);
* the SimArm's force reading (with the arm file's ``ft_sensor``): the wrist's reaction on
  the flange (``InsertionPhysics.external_force_b``), its noise seeded by ``seed`` on a
  stream of its own, so no other draw changes with it;
* the SimGripper, its object width the plug's thickness;
* the SimTactileSensor on the gel coupling (``coupling``) with the scene's appearance and
  ``sensor:`` timing and image effects (latency, capture jitter, blur, lighting drift; the
  camera file's pixel noise), its randomness seeded by its configuration's seed and ``seed``;
* a SimGamepad when a gamepad configuration is given.

The devices carry nothing of the truth: the world reaches them only through the clock's
and the camera's private references. The truth is ``InsertionSim.truth`` (``TruthLog``).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from core.clock import Clock, ManualClock, MonotonicClock, PacedClock
from core.task_geometry import HolePose, PlugGeometry
from drivers.sim.gel.model import GelModel
from drivers.sim.gel.profile import ObjectShape, gel_profile
from drivers.sim.render.image_effects import ImageEffects
from drivers.sim.scenes.insertion.coupling import GelCoupling
from drivers.sim.scenes.insertion.draws import SceneDraw, draw_scene
from drivers.sim.scenes.insertion.frames import upright_pose
from drivers.sim.scenes.insertion.physics import InsertionPhysics
from drivers.sim.scenes.insertion.scene_clock import SceneClock
from drivers.sim.scenes.insertion.scene_config import InsertionSceneConfig, check_fits
from drivers.sim.scenes.insertion.truth import TruthLog
from drivers.sim.scenes.insertion.world import InsertionWorld
from drivers.sim.twins.arm import SimArm, SimArmConfig
from drivers.sim.twins.gamepad import SimGamepad, SimGamepadConfig
from drivers.sim.twins.gripper import SimGripper, SimGripperConfig
from drivers.sim.twins.tactile import SensorTiming, SimTactileConfig, SimTactileSensor

FORCE_NOISE_STREAM = 0xF0
"""The first word of the arm's force-noise generator's seed (the second is the trial's)."""


@dataclass(frozen=True)
class SimDevices:
    """The twins' configurations (``backend: sim``)."""

    arm: SimArmConfig
    gripper: SimGripperConfig
    tactile: SimTactileConfig
    gamepad: SimGamepadConfig | None = None


@dataclass
class InsertionSim:
    """A built scene. The controller gets ``clock``, ``arm``, ``gripper``, ``tactile`` and
    ``gamepad``; ``truth`` and ``draw`` (the seed's hole, board and grasp) go to the run's
    record only. ``sync()`` brings the world to the
    clock's present (e.g. before reading the truth at the end of a run)."""

    clock: SceneClock
    arm: SimArm
    gripper: SimGripper
    tactile: SimTactileSensor
    gamepad: SimGamepad | None
    truth: TruthLog
    world: InsertionWorld
    draw: SceneDraw

    def sync(self) -> None:
        self.world.sync(self.clock.now())


def scene_arm_config(
    arm: SimArmConfig, scene: InsertionSceneConfig, plug: PlugGeometry, hole: HolePose
) -> SimArmConfig:
    """``arm`` starting upright over ``hole`` (its envelope unchanged): the tip
    ``start_above_hole_m`` above it, or ``start_depth_m`` below its surface when set."""
    tip_z_m = (
        hole.z_m + scene.start_above_hole_m
        if scene.start_depth_m is None
        else hole.z_m - scene.start_depth_m
    )
    start = upright_pose((hole.x_m, hole.y_m, tip_z_m + plug.length_m), hole.yaw_rad)
    (x, y, z), (roll, pitch, yaw) = start.xyz_m, start.rpy_rad
    sim = dataclasses.replace(
        arm.sim,
        start_x_m=x,
        start_y_m=y,
        start_z_m=z,
        start_roll_rad=roll,
        start_pitch_rad=pitch,
        start_yaw_rad=yaw,
    )
    return dataclasses.replace(arm, sim=sim)


def build_insertion_sim(
    scene: InsertionSceneConfig,
    plug: PlugGeometry,
    hole_nominal: HolePose,
    devices: SimDevices,
    seed: int,
    realtime: bool = False,
    paced: bool = False,
) -> InsertionSim:
    """The scene for one trial (see the module docstring); ValueError if the plug does not
    fit the opening or the start pose leaves the arm's envelope."""
    check_fits(scene, plug)
    draw = draw_scene(hole_nominal, scene, seed)
    hole = draw.hole
    base: Clock = ManualClock()  # every choice starts at 0
    if realtime:
        base = PacedClock() if paced else MonotonicClock.from_now()
    clock = SceneClock(base)
    # the trials start over the nominal hole; the alignment demo (start_depth_m) in the true one
    start_hole = hole_nominal if scene.start_depth_m is None else hole
    arm_config = scene_arm_config(devices.arm, scene, plug, start_hole)
    start = arm_config.sim.start_pose
    arm = SimArm(arm_config, clock)
    gripper_sim = dataclasses.replace(devices.gripper.sim, object_width_m=plug.thickness_m)
    gripper = SimGripper(dataclasses.replace(devices.gripper, sim=gripper_sim), clock)
    truth = TruthLog(hole=hole, hole_nominal=hole_nominal)
    physics = InsertionPhysics(
        scene, plug, hole, start, clock.now(), truth, draw.board_tilt_rad, draw.grasp
    )
    world = InsertionWorld(physics, arm, gripper, plug.thickness_m, start)
    arm.attach_force_source(
        physics.external_force_b, np.random.default_rng([FORCE_NOISE_STREAM, seed])
    )
    clock.attach(world.sync)
    profile = gel_profile(devices.tactile.model)
    gel = GelModel(profile, ObjectShape("square_peg", plug.width_m, "y"))
    sensor = scene.sensor
    tactile = SimTactileSensor(
        devices.tactile,
        clock,
        rng=np.random.default_rng([devices.tactile.sim.seed, seed]),
        field_source=GelCoupling(world, gel, draw.grasp),
        appearance=scene.tactile_appearance,
        effects=ImageEffects(
            noise_grey=devices.tactile.sim.noise_grey,
            blur_sigma_px=sensor.blur_sigma_px,
            drift_gain_per_level=sensor.drift_gain_per_level,
        ),
        timing=SensorTiming(sensor.latency_s, sensor.jitter_s, sensor.drift_period_s),
    )
    gamepad = None if devices.gamepad is None else SimGamepad(devices.gamepad, clock)
    return InsertionSim(clock, arm, gripper, tactile, gamepad, truth, world, draw)


def build_world(spec: Any, configs: Mapping[str, Any]) -> InsertionSim:
    """The registry's entry (``drivers.registry.build_device_set``): the scene of ``spec``
    (a ``registry.WorldSpec``) with the twins of ``configs`` (kind -> the device file's
    ``backend: sim`` configuration)."""
    devices = SimDevices(**configs)
    return build_insertion_sim(
        spec.scene, spec.plug, spec.hole, devices, spec.seed, spec.realtime, spec.paced
    )
