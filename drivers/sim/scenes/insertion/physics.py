"""The MuJoCo side of the insertion scene: the model, its stepping with the commanded TCP,
the grasp's wrench and the ground truth.

``InsertionPhysics(scene, plug, hole_true, start_pose, t0_s, truth, board_tilt_rad,
grasp)`` builds the model of ``mjcf.scene_xml`` (the board tilted and the plug placed in
the fingers as drawn; nominal by default). ``step_to(t_s, pose_t_s, pose)`` advances in
fixed steps of ``timestep_s`` up to ``t_s`` with the mocap TCP moving linearly (position; normalised
linear interpolation of the quaternion) from its last pose to ``pose`` reached at
``pose_t_s`` and held after it. Each step keeps the grasp's wrench in a ring buffer
(``grasp_wrench_at``: the wrench at a past step, for the tactile frames) and the ground
truth's running contact-force maxima (the summed normal force, and the net force along the
hole's axis); a ``TruthLog`` row is written every
``1 / truth_rate_hz`` s.

The grasp's wrench is the wrench the gripper exerts on the plug through the gel spring,
in S's axes about the grasp point on the plug's axis (MuJoCo's force/torque sensors at the
plug body's origin: the interaction between the plug and its parent; it includes the
plug's own weight and inertia, as a real grasp carries them).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from core.devices import Pose
from core.task_geometry import HolePose, PlugGeometry
from drivers.sim.scenes.insertion.draws import NOMINAL_GRASP, GraspPose
from drivers.sim.scenes.insertion.frames import S_IN_T, quat_wxyz_from_pose
from drivers.sim.scenes.insertion.mjcf import board_rotation, scene_xml
from drivers.sim.scenes.insertion.scene_config import InsertionSceneConfig
from drivers.sim.scenes.insertion.truth import TRUTH_WIDTH, TruthLog

RING_S = 1.0  # how far back the grasp's wrench is kept, s
_WRIST = ("wrist_x", "wrist_y", "wrist_z", "wrist_rx", "wrist_ry", "wrist_rz")
_GEL = ("gel_x", "gel_y", "gel_z", "gel_rx", "gel_ry", "gel_rz")
_IN_PAD_PLANE = [0, 1, 5]  # gel_x, gel_y, gel_rz: slides along x_S, y_S and the turn about z_S
_BAD_STATE = (
    mujoco.mjtWarning.mjWARN_BADQPOS,
    mujoco.mjtWarning.mjWARN_BADQVEL,
    mujoco.mjtWarning.mjWARN_BADQACC,
)
_RELEASED_DAMPING = 1e-4  # the gel joints' damping once the fingers let go (numerical only)


def _index(addresses: list[int]) -> slice | np.ndarray:
    """Addresses into MuJoCo's arrays: a slice when they are consecutive (a view, as fast
    as an attribute), else an index array."""
    first = int(addresses[0])
    if [int(a) for a in addresses] == list(range(first, first + len(addresses))):
        return slice(first, first + len(addresses))
    return np.array(addresses)


class UnstablePhysicsError(RuntimeError):
    """MuJoCo found a non-finite or huge position, velocity or acceleration (and reset its
    state)."""


class InsertionPhysics:
    """See the module docstring. ``truth`` receives the rows; ``share`` scales the grasp's
    wrench to the sensing gel's (``gel_spring.load_share``) in the truth's ``gel_wrench_s``."""

    def __init__(
        self,
        scene: InsertionSceneConfig,
        plug: PlugGeometry,
        hole_true: HolePose,
        start_pose: Pose,
        t0_s: float,
        truth: TruthLog,
        board_tilt_rad: tuple[float, float] = (0.0, 0.0),
        grasp: GraspPose = NOMINAL_GRASP,
    ) -> None:
        xml = scene_xml(scene, plug, hole_true, board_tilt_rad, grasp)
        self.model = mujoco.MjModel.from_xml_string(xml)
        self.data = mujoco.MjData(self.model)
        self.dt_s = self.model.opt.timestep
        self._share = scene.gel_spring.load_share
        self._hole_z = hole_true.z_m
        self._truth = truth
        m = self.model
        self._tip = m.site("tip").id
        self._plug = m.body("plug").id
        self._gripper = m.body("gripper").id
        self._condim = int(m.geom("plug").condim[0])
        # The hole's axis in B (out of the board): H's z on the board as built.
        self._hole_axis_b = board_rotation(hole_true, board_tilt_rad).apply([0.0, 0.0, 1.0])
        force = m.sensor_adr[m.sensor("gel_force").id]
        if m.sensor_adr[m.sensor("gel_torque").id] != force + 3:
            raise AssertionError("mjcf: the grasp's torque sensor must follow its force sensor")
        self._grasp = slice(int(force), int(force) + 6)
        wrist = [m.joint(name) for name in _WRIST]
        self._wrist_j = _index([j.id for j in wrist])
        self._wrist_q = _index([j.qposadr[0] for j in wrist])
        self._wrist_v = _index([j.dofadr[0] for j in wrist])
        gel = [m.joint(name) for name in _GEL]
        self._gel_j = np.array([j.id for j in gel])
        self._gel_q = np.array([j.qposadr[0] for j in gel])
        self._gel_v = np.array([j.dofadr[0] for j in gel])
        self._gel_stiffness = m.jnt_stiffness[self._gel_j].copy()
        self._gel_damping = m.dof_damping[self._gel_v].copy()
        self._slide_j = _index([j.id for j in gel[:3]])
        self._slide_v = _index([j.dofadr[0] for j in gel[:3]])
        if not isinstance(self._slide_j, slice) or not isinstance(self._slide_v, slice):
            # the step loop reads them as views bound once (an index array would be a copy)
            raise AssertionError("mjcf: the gel's slide joints must be consecutive")
        bad_state = _index([int(w) for w in _BAD_STATE])
        if not isinstance(bad_state, slice):
            raise AssertionError("mujoco: the bad-state warnings must be consecutive")
        self._bad_state_counts = self.data.warning.number[bad_state]  # a view, read per call
        self.released = False
        self.loose = False  # the fingers slightly open: the pads bound the plug (``loosen``)
        self._pos = np.array(start_pose.xyz_m, float)
        self._quat = quat_wxyz_from_pose(start_pose)
        self.data.mocap_pos[0] = self._pos
        self.data.mocap_quat[0] = self._quat
        mujoco.mj_forward(m, self.data)
        self.t_s = float(t0_s)
        self._t0_s = float(t0_s)
        self._steps = 0
        n_ring = max(2, math.ceil(RING_S / self.dt_s))
        self._ring = np.zeros((n_ring, 6))
        self._ring[0] = self._grasp_now()
        self._truth_every = max(1, round(1.0 / (scene.truth_rate_hz * self.dt_s)))
        self._peak_force_n = 0.0
        self._peak_axial_n = 0.0
        self._record()

    # ----------------------------------------------------------------- stepping

    def step_to(self, t_s: float, pose_t_s: float, pose: Pose) -> None:
        """Advance to ``t_s`` (whole steps; no-op for a past time), the TCP moving toward
        ``pose`` reached at ``pose_t_s`` (see the module docstring)."""
        target = math.floor((t_s - self._t0_s) / self.dt_s + 1e-9)
        n = target - self._steps
        if n <= 0:
            return
        m, d = self.model, self.data
        times = self._t0_s + (self._steps + np.arange(1, n + 1)) * self.dt_s
        span = pose_t_s - self.t_s
        if span <= 0:
            share = np.ones(n)
        else:  # np.clip's and np.linalg.norm's ufuncs without their wrappers (~10 us a call)
            share = np.minimum(np.maximum((times - self.t_s) / span, 0.0), 1.0)
        end_pos = np.array(pose.xyz_m, float)
        end_quat = quat_wxyz_from_pose(pose)
        if float(np.dot(end_quat, self._quat)) < 0:
            end_quat = -end_quat
        positions = self._pos + share[:, None] * (end_pos - self._pos)
        quats = self._quat + share[:, None] * (end_quat - self._quat)
        quats /= np.sqrt(np.add.reduce(quats * quats, axis=1, keepdims=True))
        # Views and counters bound once: this loop runs at 2 kHz of simulated time.
        ring, n_ring = self._ring, len(self._ring)
        grasp = d.sensordata[self._grasp]  # a fixed buffer (efc_force is not: read it anew)
        mocap_pos, mocap_quat = d.mocap_pos, d.mocap_quat
        every, condim = self._truth_every, self._condim
        step, total_of = mujoco.mj_step, np.add.reduce
        # The plug's only contacts are the board's and the receptacle's, and its slide joints
        # (relative to the gripper) are orthonormal and unlimited: their constraint forces
        # are the net contact force on the plug along their axes (xaxis, in B).
        slide_forces, slide_axes = d.qfrc_constraint[self._slide_v], d.xaxis[self._slide_j]
        hole_axis = self._hole_axis_b
        released, steps, peak = self.released, self._steps, self._peak_force_n
        peak_axial = self._peak_axial_n
        for i in range(n):
            if released:
                self._leave_plug(positions[i])
            mocap_pos[0] = positions[i]
            mocap_quat[0] = quats[i]
            step(m, d)
            steps += 1
            ring[steps % n_ring] = grasp
            ncon = d.ncon
            if ncon:
                # Elliptic cones: a contact's rows are its normal force, then its friction;
                # the contacts' rows come last, and every contact has the plug's condim.
                nefc = d.nefc
                if ncon == 1:  # the sum of one row is that row
                    total = float(d.efc_force[nefc - condim])
                else:
                    total = float(total_of(d.efc_force[nefc - ncon * condim : nefc : condim]))
                if total > peak:
                    peak = total
                axial = float(slide_forces @ (slide_axes @ hole_axis))
                if axial > peak_axial:
                    peak_axial = axial
            if steps % every == 0:
                self.t_s, self._steps = float(times[i]), steps
                self._peak_force_n, self._peak_axial_n = peak, peak_axial
                self._record()
                peak = peak_axial = 0.0
        self._steps, self._peak_force_n, self._peak_axial_n = steps, peak, peak_axial
        self.t_s = float(times[-1])
        self._pos, self._quat = positions[-1].copy(), quats[-1].copy()
        if self._bad_state_counts.any():
            # MuJoCo has reset the state: the run's physics is no longer the scene's.
            raise UnstablePhysicsError(
                f"insertion scene: the physics went unstable before t = {self.t_s:.4f} s "
                "(MuJoCo reset it); use a smaller scene.timestep_s or softer springs"
            )

    # ----------------------------------------------------------------- the grasp

    def grasp_wrench_at(self, t_s: float) -> np.ndarray:
        """The grasp's wrench (6,) in S about the grasp point at the last step at or before
        ``t_s`` (within the last ``RING_S`` s; the oldest kept otherwise), N and N*m."""
        step = math.floor((t_s - self._t0_s) / self.dt_s + 1e-9)
        step = min(max(step, self._steps - len(self._ring) + 1, 0), self._steps)
        return self._ring[step % len(self._ring)].copy()

    def gel_wrench_at(self, t_s: float) -> np.ndarray:
        """The sensing gel's share of the grasp's wrench at ``t_s`` (see ``TruthLog``)."""
        return self._share * self.grasp_wrench_at(t_s)

    def release(self) -> None:
        """The fingers let go: the gel spring carries nothing (the plug moves freely)."""
        if self.released:
            return
        self.model.jnt_stiffness[self._gel_j] = 0.0
        self.model.dof_damping[self._gel_v] = _RELEASED_DAMPING
        self.released = True

    def loosen(self) -> None:
        """The fingers open a little (a re-grasp): the plug is free in the pads' plane (it
        slides along x_S and y_S and turns about z_S), while the pads, a fraction of a
        millimetre off its faces, still hold it square to them and between them (the scene
        has no finger geometry: freeing every joint let a re-grasped plug turn 80 degrees
        out of the pads' plane before they closed again)."""
        if self.released or self.loose:
            return
        free_j, free_v = self._gel_j[_IN_PAD_PLANE], self._gel_v[_IN_PAD_PLANE]
        self.model.jnt_stiffness[free_j] = 0.0
        self.model.dof_damping[free_v] = _RELEASED_DAMPING
        self.loose = True

    def _leave_plug(self, tcp_xyz: np.ndarray) -> None:
        """Keep a released plug where it is as the TCP moves: MuJoCo moves a mocap body by
        setting its position, which carries its children along without a velocity, so the
        free plug (its joints are relative to the gripper) would be lifted with every step
        of the retracting arm and knocked back by the board (the resting plug's contact
        force then peaked at 16 times its weight). The gel's slide joints take up the TCP's
        translation; its rotation (the arm holds its orientation while retracting) is not
        taken up."""
        d = self.data
        axes = d.xmat[self._gripper].reshape(3, 3) @ S_IN_T  # the slides' axes in B
        d.qpos[self._gel_q[:3]] -= axes.T @ (tcp_xyz - d.mocap_pos[0])

    def grasp(self) -> None:
        """The fingers close on the plug where it is: the gel spring's rest is its pose."""
        if not (self.released or self.loose):
            return
        self.model.qpos_spring[self._gel_q] = self.data.qpos[self._gel_q]
        self.model.jnt_stiffness[self._gel_j] = self._gel_stiffness
        self.model.dof_damping[self._gel_v] = self._gel_damping
        self.released = self.loose = False

    # ----------------------------------------------------------------- truth

    def wrist_wrench(self) -> np.ndarray:
        """The wrench (6,) of the wrist's springs and dampers on the gripper along its
        joint axes (T's at rest), N and N*m."""
        m, d = self.model, self.data
        q = d.qpos[self._wrist_q] - m.qpos_spring[self._wrist_q]
        k = m.jnt_stiffness[self._wrist_j]
        return -(k * q + m.dof_damping[self._wrist_v] * d.qvel[self._wrist_v])

    def external_force_b(self) -> tuple[float, float, float]:
        """The external force on the tool as a force sensor at the flange (the mocap TCP)
        reads it, in B, N: the reaction of the wrist's springs and dampers on the flange
        (``-wrist_wrench``'s force, turned from T's axes into B). The tool's weight is not in
        it (the scene compensates it, as the arm's payload setting does)."""
        force_t = -self.wrist_wrench()[:3]
        rotation = np.empty(9)
        mujoco.mju_quat2Mat(rotation, self.data.mocap_quat[0])
        fx, fy, fz = (float(v) for v in rotation.reshape(3, 3) @ force_t)
        return (fx, fy, fz)

    def tip_xyz(self) -> np.ndarray:
        """The plug's tip in B, m."""
        return self.data.site_xpos[self._tip].copy()

    def plug_quat(self) -> np.ndarray:
        """The plug's orientation S2B, (w, x, y, z)."""
        return self.data.xquat[self._plug].copy()

    def _grasp_now(self) -> np.ndarray:
        return self.data.sensordata[self._grasp].copy()

    def _record(self) -> None:
        d = self.data
        row = np.empty(TRUTH_WIDTH)
        row[0] = self.t_s
        np.multiply(self._share, d.sensordata[self._grasp], out=row[1:7])
        row[7:13] = self.wrist_wrench()
        row[13:16] = d.site_xpos[self._tip]
        row[16:20] = d.xquat[self._plug]
        row[20] = self._hole_z - row[15]
        row[21] = self._peak_force_n
        row[22] = self._peak_axial_n
        self._truth.append(row)
        self._peak_force_n = self._peak_axial_n = 0.0
