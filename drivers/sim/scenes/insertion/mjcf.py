"""The scene's MJCF, built from the configuration: board and receptacle, the commanded TCP
(a mocap body), the gripper behind the compliant wrist and the plug in the gel spring.

Bodies and frames (every name below is looked up by name in ``physics``):

* ``board`` (static) at the TRUE hole pose H, turned by the board's drawn tilt: origin at
  the opening's centre on the board surface, x along the opening's width, z up (B's z). The
  board is boxes: four blocks around the opening from the surface down to ``depth_m`` and a
  base below them whose top is the receptacle's floor. Its top surface is ``size_x_m`` x
  ``size_y_m`` around H.
* ``tcp`` (mocap): the commanded tool frame T (the SimArm's pose; z along the tool, down
  when the tool points down).
* ``gripper``: at the wrist's pivot, ``pivot_above_tcp_m`` from the TCP back along the
  tool axis, axes as T's when the wrist is at rest; six joints (slide x, y, z, hinge x, y,
  z of T) with the wrist's stiffness and damping, the tilt and z joints stopped at the
  wrist's travel. Its weight is compensated
  (``gravcomp``), as the arm's payload setting does: hanging below the pivot, 0.9 kg would
  add about 0.8 N*m/rad of pendulum stiffness to the tilt spring's 0.5 and pull a
  commanded tilt mostly back to vertical, so the configured rates would not be the ones
  that act. It has no collision geometry.
* ``plug``: at the grasp point (the TCP when nothing deflects), axes those of the sensor
  frame S (``frames.S_IN_T``); six joints (slide x, y, z, hinge x, y, z of S) with the gel
  spring's stiffness and damping. A box ``width_m`` x (``length_m`` + 5 mm above the grasp)
  x ``thickness_m``, the only body that collides, placed in the body's frame by the drawn
  grasp (``draws.GraspPose``: the plug tilted and shifted in the fingers; the gel's spring
  and its sensors stay at the nominal grasp point, where the fingers are). Sites: ``grasp``
  at the body's origin, carrying the force/torque sensors of the grasp (the gripper's wrench
  on the plug in S's axes about the grasp point), ``tip`` at the plug's tip on its axis.

MuJoCo does the rigid contacts (elliptic friction cones, ``contact`` solref/solimp), the
joint springs and the integration (``implicitfast``); nothing here is a solver. Elliptic,
not pyramidal, cones: at 0.5 ms steps a plug dragged over the board under pyramidal cones
chattered (its contact force swinging by 28 % of the mean at 133 Hz); see
docs/SIMULATION.md, "Contact artefacts".
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from core.task_geometry import HolePose, PlugGeometry
from drivers.sim.scenes.insertion.draws import NOMINAL_GRASP, GraspPose
from drivers.sim.scenes.insertion.frames import S_IN_T_QUAT_WXYZ
from drivers.sim.scenes.insertion.scene_config import InsertionSceneConfig

PLUG_ABOVE_GRASP_M = 0.005  # the plug's box reaches this far above the grasp point, m
_GRIPPER_SIZE_M = (0.08, 0.05, 0.12)  # the gripper body's inertia box, m


def _vec(values) -> str:
    return " ".join(f"{float(v):.9g}" for v in values)


def _box_inertia(mass: float, size: tuple[float, float, float]) -> tuple[float, float, float]:
    a, b, c = size
    return (mass * (b * b + c * c) / 12, mass * (a * a + c * c) / 12, mass * (a * a + b * b) / 12)


def _joint(
    name: str,
    kind: str,
    axis: str,
    stiffness: float,
    damping: float,
    armature: float = 0.0,
    travel: float | None = None,
) -> str:
    vector = {"x": "1 0 0", "y": "0 1 0", "z": "0 0 1"}[axis]
    limits = "" if travel is None else f' range="{-travel:.9g} {travel:.9g}"'
    return (
        f'<joint name="{name}" type="{kind}" axis="{vector}" stiffness="{stiffness:.9g}" '
        f'damping="{damping:.9g}" armature="{armature:.9g}"{limits}/>'
    )


def stable_armature(stiffness: float, inertia: float, timestep_s: float) -> float:
    """The armature (kg or kg*m^2) that keeps a spring's mode at most ``1 / timestep_s``
    rad/s: MuJoCo integrates joint stiffness explicitly, and about its own axis the plug
    (a few 1e-8 kg*m^2) would ring at several times that under the gel's rotational spring.
    Zero when the body's own ``inertia`` about the joint suffices."""
    return max(0.0, stiffness * timestep_s**2 - inertia)


def board_blocks(scene: InsertionSceneConfig) -> list[tuple[str, tuple, tuple]]:
    """(name, centre in H, half sizes) of the board's boxes, m."""
    r, b = scene.receptacle, scene.board
    w, h, d = r.width_m / 2, r.height_m / 2, r.depth_m
    sx, sy = b.size_x_m / 2, b.size_y_m / 2
    base = b.thickness_m - r.depth_m
    side = (sx - w) / 2
    end = (sy - h) / 2
    return [
        ("wall_xn", (-(w + side), 0.0, -d / 2), (side, sy, d / 2)),
        ("wall_xp", (w + side, 0.0, -d / 2), (side, sy, d / 2)),
        ("wall_yn", (0.0, -(h + end), -d / 2), (w, end, d / 2)),
        ("wall_yp", (0.0, h + end, -d / 2), (w, end, d / 2)),
        ("floor", (0.0, 0.0, -d - base / 2), (sx, sy, base / 2)),
    ]


def _quat_wxyz(rotation: Rotation) -> tuple[float, float, float, float]:
    x, y, z, w = (float(v) for v in rotation.as_quat())
    return (w, x, y, z)


def board_rotation(hole: HolePose, board_tilt_rad: tuple[float, float]) -> Rotation:
    """H2B of the board as built: turned to the hole's yaw about B's z, then tilted by
    ``board_tilt_rad`` about H's x and then its y (rad)."""
    return Rotation.from_euler("z", hole.yaw_rad) * Rotation.from_euler("xy", board_tilt_rad)


def scene_xml(
    scene: InsertionSceneConfig,
    plug: PlugGeometry,
    hole_true: HolePose,
    board_tilt_rad: tuple[float, float] = (0.0, 0.0),
    grasp: GraspPose = NOMINAL_GRASP,
) -> str:
    """The MJCF text of the scene with the board at ``hole_true`` turned by
    ``board_tilt_rad`` about H's x, then y, and the plug in the fingers at ``grasp`` (see
    the module doc)."""
    wrist, spring, contact = scene.wrist, scene.gel_spring, scene.contact
    solref = _vec(contact.solref)
    solimp = _vec(contact.solimp)
    friction = f"{scene.friction:.9g} 0.005 0.0001"
    # Frictionless contacts have one dimension: a pyramid of zero friction is degenerate.
    condim = 1 if scene.friction == 0 else 3
    board_quat = _quat_wxyz(board_rotation(hole_true, board_tilt_rad))
    blocks = "\n".join(
        f'<geom name="{name}" type="box" pos="{_vec(pos)}" size="{_vec(half)}" '
        f'contype="2" conaffinity="1" condim="{condim}" friction="{friction}" solref="{solref}" '
        f'solimp="{solimp}" rgba="0.3 0.5 0.3 1"/>'
        for name, pos, half in board_blocks(scene)
    )
    g_mass = scene.gripper_mass_kg
    g_inertia = _box_inertia(g_mass, _GRIPPER_SIZE_M)
    pivot = wrist.pivot_above_tcp_m
    length = plug.length_m + PLUG_ABOVE_GRASP_M
    p_mass = spring.plug_mass_kg
    p_size = (plug.width_m, length, plug.thickness_m)
    p_inertia = _box_inertia(p_mass, p_size)
    p_centre_y = (plug.length_m - PLUG_ABOVE_GRASP_M) / 2
    # The plug's inertia about the grasp point matters for the gel spring's stability; its
    # centre of mass is the box's.
    half_plug = (plug.width_m / 2, length / 2, plug.thickness_m / 2)
    # The plug's box, its centre of mass and its tip, placed by the grasp in the body's
    # frame (S at the nominal grasp point, where the gel's spring acts).
    turn = grasp.rotation()
    plug_quat = _quat_wxyz(Rotation.from_matrix(turn))
    centre = grasp.place(np.array([0.0, p_centre_y, 0.0]))
    tip = grasp.place(np.array([0.0, plug.length_m, 0.0]))
    wrist_joints = "\n".join(
        [
            _joint(f"wrist_{a}", "slide", a, wrist.xy_stiffness_n_m, wrist.xy_damping_n_s_m)
            for a in "xy"
        ]
        + [
            _joint(
                "wrist_z",
                "slide",
                "z",
                wrist.z_stiffness_n_m,
                wrist.z_damping_n_s_m,
                travel=wrist.z_travel_m,
            )
        ]
        + [
            _joint(
                f"wrist_r{a}",
                "hinge",
                a,
                wrist.tilt_stiffness_nm_rad,
                wrist.tilt_damping_nm_s_rad,
                travel=wrist.tilt_travel_rad,
            )
            for a in "xy"
        ]
        + [
            _joint(
                "wrist_rz", "hinge", "z", wrist.twist_stiffness_nm_rad, wrist.twist_damping_nm_s_rad
            )
        ]
    )
    dt = scene.timestep_s
    k, k_rot = spring.stiffness_n_m, spring.rotational_stiffness_nm_rad
    # about the grasp point (parallel axes; the centre of mass is off it), for the armature
    about_grasp = np.diag(turn @ np.diag(p_inertia) @ turn.T) + p_mass * (
        float(centre @ centre) - centre**2
    )
    gel_joints = "\n".join(
        [
            _joint(f"gel_{a}", "slide", a, k, spring.damping_n_s_m, stable_armature(k, p_mass, dt))
            for a in "xyz"
        ]
        + [
            _joint(
                f"gel_r{a}",
                "hinge",
                a,
                k_rot,
                spring.rotational_damping_nm_s_rad,
                stable_armature(k_rot, inertia, dt),
            )
            for a, inertia in zip("xyz", about_grasp, strict=True)
        ]
    )
    return f"""
<mujoco model="insertion">
  <compiler angle="radian" autolimits="true"/>
  <option timestep="{scene.timestep_s:.9g}" integrator="implicitfast" cone="elliptic"/>
  <worldbody>
    <body name="board" pos="{_vec((hole_true.x_m, hole_true.y_m, hole_true.z_m))}"
          quat="{_vec(board_quat)}">
{blocks}
    </body>
    <body name="tcp" mocap="true">
      <body name="gripper" pos="0 0 {-pivot:.9g}" gravcomp="1">
        <inertial pos="0 0 {pivot / 2:.9g}" mass="{g_mass:.9g}"
                  diaginertia="{_vec(g_inertia)}"/>
{wrist_joints}
        <site name="wrist" pos="0 0 0"/>
        <body name="plug" pos="0 0 {pivot:.9g}" quat="{_vec(S_IN_T_QUAT_WXYZ)}">
          <inertial pos="{_vec(centre)}" quat="{_vec(plug_quat)}" mass="{p_mass:.9g}"
                    diaginertia="{_vec(p_inertia)}"/>
{gel_joints}
          <geom name="plug" type="box" pos="{_vec(centre)}" quat="{_vec(plug_quat)}"
                size="{_vec(half_plug)}"
                contype="1" conaffinity="2" condim="{condim}" friction="{friction}"
                solref="{solref}" solimp="{solimp}" mass="0" rgba="0.8 0.8 0.85 1"/>
          <site name="grasp" pos="0 0 0"/>
          <site name="tip" pos="{_vec(tip)}"/>
        </body>
      </body>
    </body>
  </worldbody>
  <sensor>
    <force name="gel_force" site="grasp"/>
    <torque name="gel_torque" site="grasp"/>
    <force name="wrist_force" site="wrist"/>
    <torque name="wrist_torque" site="wrist"/>
  </sensor>
</mujoco>
"""
