"""The insertion scene's configuration: the ``scene:`` section of a task YAML, and the plug
and nominal hole the caller passes in (the controller needs those too, so they live in the
task's ``plug:`` and ``hole:`` sections, read by the trial runner).

Task YAML layout (``configs/tasks/usb_c.yaml``; other sections belong to other readers)::

    plug:                 # PlugGeometry: the grasped plug (m)
      width_m: 0.00825
      thickness_m: 0.0024
      length_m: 0.030     # from the grasp point (TCP) to the tip
    hole:                 # HolePose: the NOMINAL opening in the base frame B
      x_m: 0.40           # centre of the opening at the board surface
      y_m: 0.0
      z_m: 0.0
      yaw_rad: 0.0        # the opening's width along B's x turned by yaw about B's z
    scene:                # InsertionSceneConfig (this module; read by controller.run.task)
      ...

Units are SI. Every number is range-checked (core/config.py); a bad value is a one-line
ConfigError naming the file and the dotted key.
"""

from __future__ import annotations

import math

from core.config import Config, config_dataclass, number
from core.task_geometry import PlugGeometry
from drivers.sim.render.appearance import appearance_names


@config_dataclass
class ReceptacleConfig(Config):
    """The opening in the board (m): ``width_m`` along H's x, ``height_m`` along H's y, and
    ``depth_m`` from the board surface to the receptacle's floor."""

    width_m: float = number(1e-3, 0.05, default=0.00834)
    height_m: float = number(5e-4, 0.02, default=0.00256)
    depth_m: float = number(1e-3, 0.05, default=0.0065)


@config_dataclass
class BoardConfig(Config):
    """The board around the opening: its top surface is ``size_x_m`` by ``size_y_m``
    (centred on the nominal hole) and ``thickness_m`` thick below the surface."""

    size_x_m: float = number(0.01, 1.0, default=0.12)
    size_y_m: float = number(0.01, 1.0, default=0.12)
    thickness_m: float = number(1e-3, 0.1, default=0.02)


@config_dataclass
class HoleUncertainty(Config):
    """The true hole is the nominal one moved by independent uniform draws in
    [-x_m, x_m], [-y_m, y_m] (m, along B) and [-yaw_rad, yaw_rad], seeded."""

    x_m: float = number(0.0, 0.05, default=0.003)
    y_m: float = number(0.0, 0.05, default=0.003)
    yaw_rad: float = number(0.0, 0.5, default=math.radians(3.0))


@config_dataclass
class GraspUncertainty(Config):
    """The plug's true pose in the fingers, drawn per seed; the machine knows only the
    nominal grasp (the plug's axis along the tool axis, centred on the gel). Independent
    uniform draws: a tilt about each of the two axes across the plug's length (S's x, the
    plug's width, and S's z, the gel's normal) in [-tilt_rad, tilt_rad]; an offset along the
    plug's length in [-along_m, along_m] (m; positive: the tip farther from the gel) and
    across its width in [-across_m, across_m] (m, along S's x)."""

    tilt_rad: float = number(0.0, 0.3, default=math.radians(5.0))
    along_m: float = number(0.0, 0.01, default=0.002)
    across_m: float = number(0.0, 0.005, default=0.001)


@config_dataclass
class BoardUncertainty(Config):
    """The board's true height and tilt, drawn per seed beside the hole's x, y and yaw:
    uniform in [-height_m, height_m] (m, along B's z) and a tilt about each of H's x and y
    axes in [-tilt_rad, tilt_rad]."""

    height_m: float = number(0.0, 0.01, default=0.001)
    tilt_rad: float = number(0.0, 0.1, default=math.radians(1.0))


@config_dataclass
class SensorTiming(Config):
    """What the tactile camera adds in the scene (drivers/sim/twins/tactile.py): a frame
    captured at ``t`` arrives (and is stamped, as the real driver stamps it) at
    ``t + latency_s``; each frame's capture time is moved from the nominal by a uniform draw
    in [-jitter_s, jitter_s] (seeded). The image effects of the renderer
    (drivers/sim/render/image_effects.py): an optical Gaussian blur of ``blur_sigma_px``
    and a lighting drift whose level grows by one per ``drift_period_s`` after connecting,
    each level changing the B, G, R gains by ``drift_gain_per_level``. Pixel noise is the
    camera file's ``sim.noise_grey``."""

    latency_s: float = number(0.0, 0.5, default=0.04)
    jitter_s: float = number(0.0, 0.019, default=0.004)
    blur_sigma_px: float = number(0.0, 5.0, default=0.3)
    drift_period_s: float = number(1.0, 1e5, default=60.0)
    drift_gain_per_level: tuple[float, float, float] = number(
        -0.1, 0.1, default=(-0.0026, 0.0047, -0.0041)
    )


@config_dataclass
class WristConfig(Config):
    """The compliant wrist between the commanded TCP and the gripper (a spring-loaded soft
    wrist; docs/SIMULATION.md, "The compliant wrist"): stiffness and damping per axis of the
    tool frame at the wrist's pivot, ``pivot_above_tcp_m`` above the TCP along the tool
    axis. ``x/y`` translation (N/m, N*s/m; the wrist is stiff there), ``z`` translation
    along the tool axis, ``tilt`` about the tool's x and y (N*m/rad, N*m*s/rad), ``twist``
    about the tool axis. Travel: the tilt stops at +-``tilt_travel_rad`` and the z
    translation at +-``z_travel_m`` (hard stops)."""

    pivot_above_tcp_m: float = number(0.0, 0.5, default=0.19)
    xy_stiffness_n_m: float = number(10.0, 1e7, default=1e5)
    xy_damping_n_s_m: float = number(0.0, 1e5, default=300.0)
    z_stiffness_n_m: float = number(1.0, 1e7, default=1000.0)
    z_damping_n_s_m: float = number(0.0, 1e5, default=10.0)
    tilt_stiffness_nm_rad: float = number(0.01, 1e4, default=0.5)
    tilt_damping_nm_s_rad: float = number(0.0, 100.0, default=0.005)
    twist_stiffness_nm_rad: float = number(0.01, 1e4, default=5.0)
    twist_damping_nm_s_rad: float = number(0.0, 100.0, default=0.05)
    tilt_travel_rad: float = number(1e-3, 1.5, default=0.095)
    z_travel_m: float = number(1e-4, 0.1, default=0.01)


@config_dataclass
class GelSpringConfig(Config):
    """The grasp: a stiff spring-damper between the gripper and the plug standing for the
    gel pads, per axis of the sensor frame S at the grasp point (translation N/m, N*s/m;
    rotation N*m/rad, N*m*s/rad). ``load_share``: the share of the grasp's wrench that the
    sensing finger's gel carries (0.5: two alike fingers). ``plug_mass_kg``: the plug and the
    part of the stick in the grasp."""

    stiffness_n_m: float = number(100.0, 1e7, default=2e4)
    damping_n_s_m: float = number(0.0, 1e4, default=20.0)
    rotational_stiffness_nm_rad: float = number(0.01, 1e4, default=2.0)
    rotational_damping_nm_s_rad: float = number(0.0, 100.0, default=0.002)
    load_share: float = number(0.05, 1.0, default=0.5)
    plug_mass_kg: float = number(1e-3, 0.5, default=0.01)


@config_dataclass
class ContactConfig(Config):
    """MuJoCo's contact softness between the plug and the board: ``solref`` (time constant
    s, damping ratio) and ``solimp`` (dmin, dmax, width m, midpoint, power); see MuJoCo's
    "Solver parameters". The time constant must be at least twice the physics time step."""

    solref: tuple[float, float] = number(1e-4, 10.0, default=(0.001, 1.0))
    solimp: tuple[float, float, float, float, float] = number(
        1e-4, 10.0, default=(0.95, 0.99, 0.0005, 0.5, 2.0)
    )

    def __post_init__(self) -> None:
        d0, d1, _, mid, _ = self.solimp
        if not (d0 < 1.0 and d1 < 1.0 and mid < 1.0):
            raise ValueError(
                f"key 'solimp': expected dmin, dmax and midpoint below 1, got {self.solimp!r}"
            )


@config_dataclass
class InsertionSceneConfig(Config):
    """The ``scene:`` section of a task YAML (see the module docstring).

    ``friction``: sliding (Coulomb) friction between the plug and the board.
    ``timestep_s``: the physics step. ``gripper_mass_kg``: the gripper body behind the
    wrist (its weight is compensated, as the arm's payload setting does). ``grip_*``: the
    tactile coupling (module ``coupling``). ``start_above_hole_m``: the SimArm starts
    upright with the plug's tip this far above the nominal hole. ``start_depth_m``: None
    (the trials' start, above the hole), or the teleoperated alignment demo's start: the
    plug upright and aligned in the **true** hole, its tip this far below the board surface
    (partly inserted; ``start_above_hole_m`` is then unused). ``truth_rate_hz``: rate of
    the ground-truth record.
    """

    receptacle: ReceptacleConfig = ReceptacleConfig()
    board: BoardConfig = BoardConfig()
    hole_uncertainty: HoleUncertainty = HoleUncertainty()
    board_uncertainty: BoardUncertainty = BoardUncertainty()
    grasp_uncertainty: GraspUncertainty = GraspUncertainty()
    sensor: SensorTiming = SensorTiming()
    wrist: WristConfig = WristConfig()
    gel_spring: GelSpringConfig = GelSpringConfig()
    contact: ContactConfig = ContactConfig()
    friction: float = number(0.0, 3.0, default=0.3)
    timestep_s: float = number(1e-4, 0.005, default=0.0005)
    gripper_mass_kg: float = number(0.05, 10.0, default=0.9)
    start_above_hole_m: float = number(0.0, 0.3, default=0.03)
    start_depth_m: float | None = number(0.0, 0.05, default=None)
    truth_rate_hz: float = number(1.0, 2000.0, default=100.0)
    tactile_appearance: str = "realistic"

    def __post_init__(self) -> None:
        names = appearance_names()
        if self.tactile_appearance not in names:
            raise ValueError(
                f"key 'tactile_appearance': expected one of {', '.join(names)}, "
                f"got {self.tactile_appearance!r}"
            )
        if self.board.thickness_m <= self.receptacle.depth_m:
            raise ValueError(
                f"key 'board.thickness_m': expected more than receptacle.depth_m "
                f"({self.receptacle.depth_m}), got {self.board.thickness_m!r}"
            )
        for axis, size, opening in (
            ("x", self.board.size_x_m, self.receptacle.width_m),
            ("y", self.board.size_y_m, self.receptacle.height_m),
        ):
            if size <= opening:
                raise ValueError(
                    f"key 'board.size_{axis}_m': expected more than the opening ({opening}), "
                    f"got {size!r}"
                )
        if self.start_depth_m is not None and self.start_depth_m >= self.receptacle.depth_m:
            raise ValueError(
                f"key 'start_depth_m': expected less than receptacle.depth_m "
                f"({self.receptacle.depth_m}), got {self.start_depth_m!r}"
            )
        if self.contact.solref[0] < 2.0 * self.timestep_s:
            raise ValueError(
                f"key 'contact.solref': expected a time constant of at least twice "
                f"timestep_s ({2.0 * self.timestep_s}), got {self.contact.solref[0]!r}"
            )


def check_fits(scene: InsertionSceneConfig, plug: PlugGeometry) -> None:
    """ValueError unless the plug fits the opening (width and thickness below the
    opening's) and reaches the floor from the grasp (length above the depth)."""
    r = scene.receptacle
    if not (plug.width_m < r.width_m and plug.thickness_m < r.height_m):
        raise ValueError(
            f"plug: expected a cross-section smaller than the opening ({r.width_m} x "
            f"{r.height_m} m), got {plug.width_m} x {plug.thickness_m} m"
        )
    if plug.length_m <= r.depth_m:
        raise ValueError(
            f"plug.length_m: expected more than the receptacle's depth ({r.depth_m} m), "
            f"got {plug.length_m}"
        )
