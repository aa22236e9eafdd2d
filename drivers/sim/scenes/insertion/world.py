"""The insertion world: the physics kept in step with the SimArm and the SimGripper.

``sync(t_s)`` brings the physics up to ``t_s`` (at most the clock's present): the mocap
TCP follows the arm twin's pose (read with ``read_status``, which integrates the twin up
to the clock's ``now()``; the twin already applies the TCP's speed and acceleration
limits), linearly between the last synced pose and the newest one. A disconnected arm
holds its last pose.

The grasp follows the gripper twin's status (read at each sync): while the fingers hold
the plug (``GripperStatus.holding``) the gel spring holds it, squeezed with the gripper's
``commanded_force_n`` (``grip_force_n``). Once the fingers open wider than the plug after
having held it, the spring lets go (the plug is free: it stays in the receptacle, or falls);
opened by at most ``PADS_BOUND_GAP_M`` beyond the plug (a re-grasp), it is free only in
the pads' plane (``InsertionPhysics.loosen``: in that gap it could tilt out of the plane by
a few degrees at most, which the scene neglects); closing on it again grasps it where it
is. Before the first grasp the plug sits between the
fingers in the spring, unsqueezed (grip force 0, no tactile contact): the scene starts with
the plug placed there.
"""

from __future__ import annotations

from core.devices import Pose
from core.errors import DeviceError
from drivers.sim.scenes.insertion.physics import InsertionPhysics
from drivers.sim.twins.arm import SimArm
from drivers.sim.twins.gripper import SimGripper

PADS_BOUND_GAP_M = 0.001
"""Fingers open by at most this beyond the plug's thickness still hold it square between
them, m: a 20 mm plug could tilt out of their plane by 3 degrees at most."""


class InsertionWorld:
    """See the module docstring."""

    def __init__(
        self,
        physics: InsertionPhysics,
        arm: SimArm,
        gripper: SimGripper,
        plug_thickness_m: float,
        start_pose: Pose,
    ) -> None:
        self.physics = physics
        self._arm = arm
        self._gripper = gripper
        self._thickness_m = plug_thickness_m
        self._pose_t_s = physics.t_s
        self._pose = start_pose
        self._held = False
        self.grip_force_n = 0.0

    def sync(self, t_s: float) -> None:
        """Advance the physics to ``t_s`` (see the module docstring)."""
        if t_s <= self.physics.t_s:
            return
        self._read_arm()
        self._read_gripper()
        self.physics.step_to(t_s, self._pose_t_s, self._pose)

    def _read_arm(self) -> None:
        if not self._arm.is_connected:
            return
        status = self._arm.read_status()
        self._pose_t_s, self._pose = status.t_s, status.tcp

    def _read_gripper(self) -> None:
        if not self._gripper.is_connected:
            return
        try:
            status = self._gripper.read_status()
        except DeviceError:  # a silent gripper (simulated fault): the grasp stays as it is
            return
        if status.holding:
            self.physics.grasp()
            self._held = True
            self.grip_force_n = self._gripper.commanded_force_n
            return
        self.grip_force_n = 0.0
        if self._held and status.width_m > self._thickness_m + PADS_BOUND_GAP_M:
            self.physics.release()
        elif self._held and status.width_m > self._thickness_m:
            self.physics.loosen()
