"""What the scene draws per seed and the machine never sees: the true hole (its x, y and yaw
about the nominal, and the board's height), the board's tilt, and the plug's pose in the
grasp (docs/SIMULATION.md, "What touch is needed for").

``draw_scene(nominal, scene, seed)`` makes one ``SceneDraw`` from ``numpy``'s generator
seeded by ``seed``: the hole's three draws first (so a seed's hole x, y and yaw are those of
the scenes before the board and grasp draws existed), then the board's height and two tilts,
then the grasp's two tilts and two offsets; every draw is uniform within the ``scene:``
section's range, so a zero range gives the nominal value.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from core.task_geometry import HolePose
from drivers.sim.scenes.insertion.scene_config import HoleUncertainty, InsertionSceneConfig


@dataclass(frozen=True)
class GraspPose:
    """The plug in the fingers, in the sensor frame S at the nominal grasp point (the
    plug's axis along y_S toward the tip): turned by ``tilt_x_rad`` about x_S (the plug's
    width) and then by ``tilt_z_rad`` about z_S (the gel's normal), and moved by
    ``across_m`` along x_S and ``along_m`` along y_S (m). All zero: the nominal grasp."""

    tilt_x_rad: float = 0.0
    tilt_z_rad: float = 0.0
    along_m: float = 0.0
    across_m: float = 0.0

    def rotation(self) -> np.ndarray:
        """The plug's axes in S (3 x 3, columns): Rz(tilt_z) @ Rx(tilt_x)."""
        ca, sa = math.cos(self.tilt_x_rad), math.sin(self.tilt_x_rad)
        cb, sb = math.cos(self.tilt_z_rad), math.sin(self.tilt_z_rad)
        rx = np.array([[1.0, 0.0, 0.0], [0.0, ca, -sa], [0.0, sa, ca]])
        rz = np.array([[cb, -sb, 0.0], [sb, cb, 0.0], [0.0, 0.0, 1.0]])
        return rz @ rx

    def offset_s(self) -> np.ndarray:
        """Where the plug's own grasp point lies in S, m."""
        return np.array([self.across_m, self.along_m, 0.0])

    def place(self, point: np.ndarray) -> np.ndarray:
        """A point given in the plug's own frame (its axis along y, m), in S."""
        return self.offset_s() + self.rotation() @ np.asarray(point, float)


NOMINAL_GRASP = GraspPose()


@dataclass(frozen=True)
class SceneDraw:
    """One seed's truth: ``hole`` the true opening (x, y, yaw, and z moved by the board's
    height), ``board_tilt_rad`` the board's turn about H's x and then its y (rad), ``grasp``
    the plug's pose in the fingers."""

    hole: HolePose
    board_tilt_rad: tuple[float, float] = (0.0, 0.0)
    grasp: GraspPose = NOMINAL_GRASP


def draw_scene(nominal: HolePose, scene: InsertionSceneConfig, seed: int) -> SceneDraw:
    """The seed's ``SceneDraw`` (see the module docstring)."""
    rng = np.random.default_rng(seed)
    hole = _draw_hole(nominal, scene.hole_uncertainty, rng)
    board, grasp = scene.board_uncertainty, scene.grasp_uncertainty
    dz, tilt_x, tilt_y = rng.uniform(-1.0, 1.0, 3) * (
        board.height_m,
        board.tilt_rad,
        board.tilt_rad,
    )
    gx, gz, along, across = rng.uniform(-1.0, 1.0, 4) * (
        grasp.tilt_rad,
        grasp.tilt_rad,
        grasp.along_m,
        grasp.across_m,
    )
    return SceneDraw(
        HolePose(hole.x_m, hole.y_m, hole.z_m + float(dz), hole.yaw_rad),
        (float(tilt_x), float(tilt_y)),
        GraspPose(float(gx), float(gz), float(along), float(across)),
    )


def _draw_hole(
    nominal: HolePose, uncertainty: HoleUncertainty, rng: np.random.Generator
) -> HolePose:
    dx, dy, dyaw = rng.uniform(-1.0, 1.0, 3) * (
        uncertainty.x_m,
        uncertainty.y_m,
        uncertainty.yaw_rad,
    )
    return HolePose(
        nominal.x_m + float(dx),
        nominal.y_m + float(dy),
        nominal.z_m,
        nominal.yaw_rad + float(dyaw),
    )
