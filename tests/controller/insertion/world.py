"""A toy world for the machine's tests: a kinematic TCP, a gripper, and a tactile estimate made
from the geometry (a board with an opening), so observation sequences follow the commands.

The estimate is synthetic, in raw estimate units, with the machine's default S->T mapping:
* below the board surface outside the opening: an axial force k_board x penetration (S's
  shear_y is T z) and a friction torque about z_T x (drag direction);
* once the tip has dropped into the opening (``caught``): a catch torque about z_T x (drag
  direction) while it moves sideways, a torque turning the plug upright, a wall contact
  level on ``normal``, an axial ``slide_load`` once 1 mm in, and a jam torque deeper
  than ``jam_depth_m`` (while ``jams`` lasts).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.spatial.transform import Rotation

from controller.insertion.interface import Command, Observation, Phase, TeleopInput
from controller.insertion.machine import InsertionMachine
from controller.insertion.machine_config import MachineConfig, NoiseFloor, s2t_matrix
from controller.tactile.wrench import WrenchEstimate
from core.devices import ArmMode, ArmState, ArmStatus, GripperObject, GripperStatus, Pose
from core.spatial import cross, rotation_from_rpy, rpy_from_rotation
from core.task_geometry import HolePose, PlugGeometry

DT_S = 0.01


def estimate(t_s: float, **values: float | bool) -> WrenchEstimate:
    """A WrenchEstimate at ``t_s``: zeros and flags off unless given."""
    base = WrenchEstimate.zero(t_s, zeroing=False, calibrated=False)
    return replace(base, degenerate=False, **values)


def arm_status(t_s: float, xyz: tuple, rpy: tuple, error_code: int = 0) -> ArmStatus:
    return ArmStatus(
        t_s=t_s,
        tcp=Pose(tuple(map(float, xyz)), tuple(map(float, rpy))),
        joints_rad=(math.nan,) * 6,
        mode=ArmMode.VELOCITY,
        state=ArmState.READY,
        error_code=error_code,
    )


def gripper_status(
    t_s: float, holding: bool, moving: bool = False, width_m: float = 0.0024, fault_code: int = 0
) -> GripperStatus:
    obj = GripperObject.CONTACT_CLOSING if holding else GripperObject.AT_TARGET
    if moving:
        obj = GripperObject.MOVING
    return GripperStatus(t_s, True, moving, obj, width_m, fault_code, "")


@dataclass
class ToyWorld:
    plug: PlugGeometry = field(default_factory=PlugGeometry)
    hole: HolePose = field(default_factory=HolePose)
    hole_offset_m: tuple[float, float] = (0.0012, -0.0009)
    hole_radius_m: float = 0.0006
    depth_limit_m: float = 0.012  # the opening's bottom below the surface
    board: bool = True
    k_board: float = 100.0  # axial force per m of penetration (estimate units)
    friction: float = 0.1
    catch: float = 0.03  # catch torque (estimate units)
    upright: float = 0.05  # upright torque per rad of tilt
    wall_normal: float = 0.05
    slide_load: float = 0.04  # axial force while the plug slides in the opening (estimate units)
    jam_depth_m: float | None = None
    jams: int = 0  # how many times the jam appears (one per INSERT)
    jam_torque: float = 0.03
    floor_drop_m: float = 0.0  # the supporting surface this far below the board's
    rim_blocks: int = 0  # how many times an upright plug stands on the opening's rim
    # torque about the plug's axis while it stands on the rim (estimate units): the slot's
    # long walls holding its yaw where the depth by touch reads it short of entered
    held_yaw_twist: float = 0.0
    # how far below the surface the plug standing on the rim sinks (one end of its leading
    # edge in the opening): the depth by touch then reads it entered
    rim_sink_m: float = 0.0
    # the plug turned in the hand by this about T y (its tip toward +T x); on the board, the
    # in-plane torque (about T y) of the tip face's width edge pressed at one end, its sign
    # that of the edge's slope, zero where the face lies flat
    grasp_tilt_rad: float = 0.0
    edge_torque: float = 0.02
    # the plug turned in the hand by this about T x (its tip toward +T y); on the board, the
    # tilt torque (about T x) of the tip face's thickness edge pressed at one end (N*m per N
    # of the axial force: the lever of half the thickness), its sign that of the edge's
    # slope; and the slot takes the plug only within ``thickness_tol_rad`` of upright in
    # that plane (None: at any tilt)
    thickness_tilt_rad: float = 0.0
    thickness_edge_m: float = 0.0012
    thickness_tol_rad: float | None = None
    noise: float = 0.0003
    # the face across the opening's rim: a tip on the board within ``rim_width_m`` outside
    # the catch region feels this tilt torque about T x (N*m; a near miss), or with
    # ``rim_names_side`` along -(u x z_B), u the unit vector from the opening to the tip (the
    # board bearing the face on the side away from the opening)
    rim_torque: float = 0.0
    rim_width_m: float = 0.0003
    rim_names_side: bool = False
    # the arm's F/T reading (ArmStatus.external_force_n, N in B), for the blind baseline: the
    # board (or the opening's floor under the tip) pushing up k_arm_n_m per m of the tip's
    # depth below it, as through a wrist of that stiffness; plus a constant bias
    arm_force: bool = True
    k_arm_n_m: float = 1000.0
    force_bias_n: float = 0.0
    # the tactile axial force (S's shear_y, T z) as the sensing finger's share of the arm's
    # push instead of the geometric one above (None): the touch spiral's force
    axial_share: float | None = None
    # a capture of the open gel leaves the estimates zeroing until the re-zero (the real
    # estimator's way; the insertion machine's tests keep the older toy without it)
    open_gel_zeroes: bool = False
    frame_every: int = 2  # ticks per new tactile estimate
    zeroing_frames: int = 3
    seed: int = 0
    teleop: TeleopInput = field(default_factory=TeleopInput)
    fault: str | None = None
    arm_error: int = 0
    gripper_fault: int = 0
    slip_gross: bool = False
    slip_suspected: bool = False
    drop_plug: bool = False

    def __post_init__(self) -> None:
        self.rng = np.random.default_rng(self.seed)
        self.s2t = s2t_matrix(("+x", "+z", "-y"))
        self.t_s = 0.0
        self.tick = 0
        self.rotation = rotation_from_rpy((math.pi, 0.0, 0.0))
        self._turned_by: Rotation | None = None
        self._turns: dict[tuple[str, ...], np.ndarray] = {}
        self.p = np.array([self.hole.x_m, self.hole.y_m, self.hole.z_m + 0.04 + self.plug.length_m])
        self.gripper_holding = False
        self.gripper_width = 0.02
        self.gripper_busy_until = -1.0
        self.gripper_target: float | None = None
        self.zeroing_left = 0
        self.open_captured = False
        self.caught = False
        self.jammed_in_this_insert = False
        self.on_rim = False
        self.v_tip = np.zeros(3)
        self.last_estimate = estimate(0.0)
        self.commands: list[Command] = []
        self.rezero_count = 0

    # -- geometry ----------------------------------------------------------------------

    def _rim_axis(self, tip: np.ndarray) -> np.ndarray:
        """The unit axis (B) of the rim's torque on a tip at ``tip`` (see ``rim_torque``)."""
        if not self.rim_names_side:
            return self._turned([1.0, 0.0, 0.0])
        u = np.array([*(tip[:2] - self.hole_xy), 0.0])
        return -cross(u / max(float(np.linalg.norm(u)), 1e-12), [0.0, 0.0, 1.0])

    def _turned(self, vector: Sequence[float]) -> np.ndarray:
        """``self.rotation.apply(vector)``, remembered (read only) while the rotation is the
        same object (``apply`` puts a new one in its place; scipy's ``apply`` is slow and a
        tick turns the same few vectors many times), keyed by the vector's exact bits."""
        if self._turned_by is not self.rotation:
            self._turned_by, self._turns = self.rotation, {}
        key = tuple(float(c).hex() for c in vector)
        turned = self._turns.get(key)
        if turned is None:
            turned = self.rotation.apply(vector)
            turned.flags.writeable = False
            self._turns[key] = turned
        return turned

    @property
    def tip(self) -> np.ndarray:
        return self.p + self.plug.length_m * self._turned(self._axis_t())

    def _axis_t(self) -> np.ndarray:
        """The plug's axis toward its tip, in T."""
        a, b = self.grasp_tilt_rad, self.thickness_tilt_rad
        return np.array([math.sin(a) * math.cos(b), math.sin(b), math.cos(a) * math.cos(b)])

    def _thickness_slope(self) -> float:
        """How much the tip face's thickness edge rises toward its +y end (B z per unit)."""
        b = self.thickness_tilt_rad
        return float(self._turned([0.0, math.cos(b), -math.sin(b)])[2])

    def _upright_in_thickness(self) -> bool:
        """The plug within ``thickness_tol_rad`` of straight down in its thickness plane."""
        if self.thickness_tol_rad is None:
            return True
        return abs(math.asin(float(np.clip(self._thickness_slope(), -1, 1)))) <= (
            self.thickness_tol_rad
        )

    def _edge_slope(self) -> float:
        """How much the tip face's width edge rises toward its +x end (B z per unit)."""
        a = self.grasp_tilt_rad
        return float(self._turned([math.cos(a), 0.0, -math.sin(a)])[2])

    @property
    def hole_xy(self) -> np.ndarray:
        return np.array([self.hole.x_m, self.hole.y_m]) + np.array(self.hole_offset_m)

    def pose(self) -> Pose:
        return Pose(tuple(map(float, self.p)), rpy_from_rotation(self.rotation))

    # -- the observation -----------------------------------------------------------------

    def observe(self) -> Observation:
        if self.tick % self.frame_every == 0:
            self.last_estimate = self._estimate()
        moving = self.t_s < self.gripper_busy_until
        holding = self.gripper_holding and not moving and not self.drop_plug
        return Observation(
            t_s=self.t_s,
            wrench=self.last_estimate,
            arm=ArmStatus(
                self.t_s,
                self.pose(),
                (math.nan,) * 6,
                ArmMode.VELOCITY,
                ArmState.READY,
                self.arm_error,
                external_force_n=self._arm_force(),
            ),
            gripper=GripperStatus(
                self.t_s,
                True,
                moving,
                GripperObject.MOVING
                if moving
                else (GripperObject.CONTACT_CLOSING if holding else GripperObject.AT_TARGET),
                self.gripper_width,
                self.gripper_fault,
                "fault" if self.gripper_fault else "",
            ),
            teleop=self.teleop,
            fault=self.fault,
        )

    def _push_n(self) -> float:
        """The board (or the opening's floor under the tip, if the slot takes the plug)
        pushing up, N."""
        tip, surface = self.tip, self.hole.z_m - self.floor_drop_m
        over_opening = np.linalg.norm(tip[:2] - self.hole_xy) < self.hole_radius_m
        over_opening = over_opening and self._upright_in_thickness()
        support = surface - self.depth_limit_m if over_opening else surface
        return self.k_arm_n_m * max(0.0, support - tip[2]) if self.board else 0.0

    def _arm_force(self) -> tuple[float, float, float] | None:
        if not self.arm_force:
            return None
        return (0.0, 0.0, self._push_n() + self.force_bias_n)

    def _estimate(self) -> WrenchEstimate:
        if self.open_captured or self.zeroing_left > 0:
            self.zeroing_left -= 1
            return WrenchEstimate.zero(self.t_s, zeroing=True, calibrated=False)
        force_t = np.zeros(3)
        torque_b = np.zeros(3)
        normal = 0.0
        surface = self.hole.z_m - self.floor_drop_m
        tip = self.tip
        z_t = self._turned([0.0, 0.0, 1.0])
        drag = np.array([self.v_tip[0], self.v_tip[1], 0.0])
        drag_axis = cross(z_t, drag) / max(float(np.linalg.norm(drag)), 0.001)
        from_hole = float(np.linalg.norm(tip[:2] - self.hole_xy))
        on_rim = 0.0 <= from_hole - self.hole_radius_m < self.rim_width_m
        in_region = from_hole < self.hole_radius_m
        in_region = in_region and self._upright_in_thickness()
        upright = float(np.dot(z_t, [0.0, 0.0, -1.0])) > math.cos(math.radians(2.0))
        if self.rim_blocks > 0 and (self.caught or self.on_rim) and upright and (tip[2] < surface):
            self.on_rim = True  # the upright plug stands on the rim: the board holds it
            in_region = False
            self.caught = False
        elif self.on_rim and tip[2] > surface + 0.0005:
            self.on_rim = False
            self.rim_blocks -= 1
        if self.board and tip[2] < surface:
            if in_region:
                self.caught = True
        else:
            self.caught = False
        if self.board and tip[2] < surface:
            if self.caught:
                angle = math.acos(float(np.clip(np.dot(z_t, [0.0, 0.0, -1.0]), -1, 1)))
                turn = cross(z_t, [0.0, 0.0, -1.0])
                axis = turn / np.linalg.norm(turn) if np.linalg.norm(turn) > 1e-12 else turn
                torque_b += self.catch * drag_axis - self.upright * angle * axis
                normal = self.wall_normal
                if self.jam_depth_m is not None and tip[2] < surface - self.jam_depth_m:
                    if self.jams > 0:
                        self.jammed_in_this_insert = True
                        torque_b += self.jam_torque * self._turned([1.0, 0.0, 0.0])
                if tip[2] < surface - self.depth_limit_m:
                    force_t[2] = self.k_board * (surface - self.depth_limit_m - tip[2])
                elif tip[2] < surface - 0.001:
                    force_t[2] = self.slide_load  # the walls' friction on a plug pushed in
            else:
                support = surface - (self.rim_sink_m if self.on_rim else 0.0)
                axial = self.k_board * max(0.0, support - tip[2])
                force_t[2] = axial
                torque_b += self.friction * axial * drag_axis
                if on_rim and axial > 0.0:
                    torque_b += self.rim_torque * self._rim_axis(tip)
                flat = math.tanh(self._edge_slope() / 0.003) * math.tanh(axial / 0.01)
                torque_b += self.edge_torque * flat * self._turned([0.0, 1.0, 0.0])
                if self.thickness_tilt_rad:  # the thickness edge's lever jumps where flat
                    side = math.tanh(self._thickness_slope() / 0.003)
                    lever = self.thickness_edge_m * side * math.tanh(axial / 0.01)
                    torque_b += lever * self._push_n() * self._turned([1.0, 0.0, 0.0])
        if self.axial_share is not None:
            force_t[2] = self.axial_share * self._push_n()
        if self.on_rim:
            torque_b += self.held_yaw_twist * z_t
        if self.jammed_in_this_insert and not (
            self.jam_depth_m is not None and tip[2] < surface - self.jam_depth_m
        ):
            self.jammed_in_this_insert = False
            self.jams -= 1
        torque_s = self.s2t.T @ self.rotation.inv().apply(torque_b)
        force_s = self.s2t.T @ force_t
        noise = self.rng.normal(0.0, self.noise, 6)
        return estimate(
            self.t_s,
            tau_x=float(torque_s[0] + noise[0]),
            tau_y=float(torque_s[1] + noise[1]),
            tau_z=float(torque_s[2] + noise[2]),
            shear_x=float(force_s[0] + noise[3]),
            shear_y=float(force_s[1] + noise[4]),
            normal=float(force_s[2] + normal + noise[5]),
            contact=bool(normal or force_t.any()),
            slip_gross=self.slip_gross,
            slip_suspected=self.slip_suspected,
        )

    # -- applying a command ------------------------------------------------------------

    def apply(self, command: Command) -> None:
        self.commands.append(command)
        if command.capture_open_tactile and self.open_gel_zeroes:
            self.open_captured = True
        if command.rezero_tactile:
            self.rezero_count += 1
            self.zeroing_left = self.zeroing_frames
            self.open_captured = False
        if command.gripper is not None:
            closing = command.gripper.width_m < self.gripper_width
            self.gripper_busy_until = self.t_s + 0.15
            if closing and command.gripper.width_m < self.plug.thickness_m:
                self.gripper_width = self.plug.thickness_m
                self.gripper_holding = True
            else:
                self.gripper_width = command.gripper.width_m
                self.gripper_holding = False
        if command.twist is not None:
            v = np.array(command.twist.linear_m_s)
            w = np.array(command.twist.angular_rad_s)
            self.v_tip = v + cross(w, self.tip - self.p)
            self.p = self.p + v * DT_S
            self.rotation = Rotation.from_rotvec(w * DT_S) * self.rotation
        self.t_s += DT_S
        self.tick += 1

    def step(self, machine: InsertionMachine) -> Command:
        command = machine.step(self.observe())
        self.apply(command)
        return command

    def run_until(
        self, machine: InsertionMachine, phases: Phase | tuple[Phase, ...], max_s: float = 60.0
    ) -> Phase:
        """Step until the machine is in one of ``phases`` (or terminal); its phase then."""
        wanted = phases if isinstance(phases, tuple) else (phases,)
        while self.t_s < max_s:
            if machine.phase in wanted or machine.phase in (Phase.DONE, Phase.FAILED):
                return machine.phase
            self.step(machine)
        return machine.phase


TOY_FLOOR = NoiseFloor(
    tilt_x=0.0002, tilt_y=0.0002, inplane=0.005, shear_x=0.002, shear_y=0.002, normal=0.002
)
"""The noise floors in the toy world's own units (its torques and forces are not the
calibrated N*m and N the task files use; its shear noise is well below the shear floor)."""


def toy_config() -> MachineConfig:
    """The machine's defaults with the floors, budgets and limits in the toy world's units
    (``TOY_FLOOR``; its axial force is ``k_board`` per m)."""
    defaults = MachineConfig()
    return replace(
        defaults,
        signals=replace(defaults.signals, noise_floor=TOY_FLOOR),
        insert=replace(defaults.insert, force_budget=0.2),
        limits=replace(
            defaults.limits, force_limit=0.5, tilt_torque_limit=0.05, inplane_torque_limit=2.5
        ),
    )


def make_machine(world: ToyWorld, config: MachineConfig | None = None) -> InsertionMachine:
    return InsertionMachine(config or toy_config(), world.plug, world.hole)


def path(machine: InsertionMachine) -> list[tuple[str, str, str]]:
    """The machine's transitions as (source, target, reason) names."""
    return [(t.source.name, t.target.name, t.reason) for t in machine.transitions]
