"""The press-spiral machine's settings: the task file's ``touch_spiral:`` section (the
product's machine, ``dipole`` and its variants, on the tactile estimate's axial force) and
its ``blind:`` section (the same machine on the arm's F/T sensor, the ``blind`` baseline).
Lengths in m, speeds in m/s, angles in rad, forces in N (the tared upward force on the tool,
z in B), times in s.
"""

from __future__ import annotations

import math
from typing import Literal

from controller.insertion.machine_config import GripperSettings
from controller.insertion.spiral.spiral_feel import RockSettings
from controller.insertion.spiral.spiral_near_miss import NearMissSettings
from controller.insertion.spiral.torque_servo import TorqueServoSettings
from core.config import Config, config_dataclass, number


@config_dataclass
class SpiralConfig(Config):
    """The task file's ``blind:`` section (see the module doc for the units).

    ``pattern``, ``pitch_m``, ``half_width_m``: the search pattern (as ``machine.search``);
    ``inner_half_width_m``: with the spiral, the passes first sweep it out to this half-width
    at every yaw, then on to ``half_width_m`` at every yaw (0: the whole spiral at one yaw
    after another); ``interleave``: with the spiral, the passes at every other yaw step turn
    it by half a turn about the opening's centre, so that the rings of neighbouring yaws fall
    halfway between each other (an opening whose yaw lies between two passes' is within reach
    of both: a target that one misses by up to half the pitch, the other passes within a
    quarter of it);
    ``touch_force_n``: the board is met; ``press_force_n``: held while sweeping;
    ``force_gain_m_s_n``: the admittance, z speed per N of force error; ``force_window``: the
    force is the mean of this many readings; ``wrist_z_stiffness_n_m``: the compliant
    wrist's axial stiffness, as the integrator measures it on the cell (the tip's drop is
    the TCP's less the wrist's compression); ``settle_band``: the press has settled within
    this share of it; ``catch_ratio``: the force under this share of the press pauses the
    pattern; ``catch_drop_m``: the tip this far below its height at the press is a catch,
    with ``catch_drop_from``: ``tip``, the TCP's drop less the wrist's compression from the
    force (a force under the press counts as the wrist extending), or ``tcp``, the same
    without crediting that extension (a reading that drops without the load stays no catch
    until the TCP itself has gone down);
    ``probe_s``: the longest a pause lasts; ``push_speed_m_s``, ``stop_force_n``: the push
    and the force that ends it; ``stall_s``, ``stall_m``: a push whose TCP has gone no more
    than ``stall_m`` lower for ``stall_s`` has ended too (the arm's own limit); ``entry_m``:
    the least drop of the tip below its height at the press that counts as in; ``sink_m``:
    while sweeping pressed, a tip this far below its height at the press has sunk into the
    opening even though the force did not drop (the walls bear the press as the pattern drags
    the plug in the opening's mouth): INSERT, ``sank`` (0: off);
    ``lift_speed_m_s``: after a jam, back up to the press at this speed;
    ``jam_skip_m``: after a jam the pattern goes on this much further along; ``tare_s``: the
    sensor's zero is averaged over this at the hover; ``sweep_speed_m_s``: along the path;
    ``descend_speed_m_s``: down to the touch; ``fall_in_m``: the TCP this far below where it
    puts the tip on the nominal board while descending to the touch, with no touch yet, means
    the plug went into the opening (more than the board's height tolerance and the wrist's
    compression under the touch force) if the tared force is still under
    ``fall_in_force_n`` (N; at ``touch_force_n``, any force short of the touch: a touch whose
    reading lags behind the fall is no fall-in under a lower one); ``yaw_step_rad``,
    ``yaw_range_rad``: the passes' yaw offsets (``yaw_offsets``); ``turn_tol_rad``: a pass's
    yaw counts as reached within this; ``hover_m``: tip height above the board between passes;
    ``move_speed_m_s``, ``rotate_speed_rad_s``; ``pose_gain_1_s``: servo gain (speed = gain
    x error), ``pose_tol_m``: a target counts as reached within this; ``retract_m``;
    ``timeout_s``: the whole run's autonomous time; ``tared_force_limit_n``: the tared
    force (N) above which the run stops (FAILED, ``limit_exceeded``); ``tilt_limit_rad``:
    the TCP's tilt from straight down (rad) above which it stops too; ``rewind``: a probe
    first takes the pattern back to where it was at the time the force's reading describes
    (the force's delay, swept past the opening), once per stretch of the pattern;
    ``open_frames``: with a tactile reading, the new frames the grasp waits for while the
    estimator takes the open gel (more than it takes)."""

    gripper: GripperSettings
    pattern: Literal["spiral", "raster"] = "spiral"
    pitch_m: float = number(1e-5, 0.01, default=0.0004)
    half_width_m: float = number(0.0, 0.05, default=0.003)
    inner_half_width_m: float = number(0.0, 0.05, default=0.0)
    interleave: bool = False
    touch_force_n: float = number(0.05, 50.0, default=1.0)
    press_force_n: float = number(0.05, 50.0, default=2.0)
    force_gain_m_s_n: float = number(1e-5, 0.05, default=0.005)
    force_window: int = number(1, 100, default=5)
    wrist_z_stiffness_n_m: float = number(10.0, 1e6, default=1000.0)
    settle_band: float = number(0.01, 1.0, default=0.2)
    catch_ratio: float = number(0.0, 1.0, default=0.4)
    catch_drop_m: float = number(1e-5, 0.02, default=0.001)
    catch_drop_from: Literal["tip", "tcp"] = "tip"
    probe_s: float = number(0.01, 10.0, default=0.5)
    push_speed_m_s: float = number(1e-4, 0.05, default=0.004)
    stop_force_n: float = number(0.1, 100.0, default=8.0)
    stall_s: float = number(0.01, 10.0, default=0.3)
    stall_m: float = number(1e-6, 0.01, default=1e-4)
    entry_m: float = number(0.0, 0.05, default=0.002)
    sink_m: float = number(0.0, 0.05, default=0.0)
    lift_speed_m_s: float = number(1e-4, 0.05, default=0.004)
    jam_skip_m: float = number(0.0, 0.05, default=0.001)
    tare_s: float = number(0.0, 5.0, default=0.2)
    sweep_speed_m_s: float = number(1e-4, 0.1, default=0.01)
    descend_speed_m_s: float = number(1e-4, 0.1, default=0.005)
    fall_in_m: float = number(0.0005, 0.05, default=0.004)
    fall_in_force_n: float = number(0.0, 50.0, default=1.0)
    yaw_step_rad: float = number(1e-4, 0.5, default=0.02)
    yaw_range_rad: float = number(0.0, 0.5, default=0.0524)
    turn_tol_rad: float = number(1e-5, 0.1, default=0.002)
    hover_m: float = number(0.0, 0.05, default=0.002)
    move_speed_m_s: float = number(1e-4, 0.2, default=0.02)
    pose_gain_1_s: float = number(0.1, 100.0, default=10.0)
    rotate_speed_rad_s: float = number(1e-3, 3.0, default=0.5)
    pose_tol_m: float = number(1e-6, 0.01, default=0.0002)
    retract_m: float = number(0.0, 0.2, default=0.03)
    timeout_s: float = number(1.0, 3600.0, default=120.0)
    tared_force_limit_n: float = number(0.1, 200.0, default=20.0)
    tilt_limit_rad: float = number(0.0, 0.5, default=0.2)
    rewind: bool = False
    open_frames: int = number(1, 100, default=6)

    def __post_init__(self) -> None:
        forces = (
            self.touch_force_n,
            self.press_force_n,
            self.stop_force_n,
            self.tared_force_limit_n,
        )
        if not forces[0] < forces[1] < forces[2] < forces[3]:
            raise ValueError(
                "keys 'touch_force_n', 'press_force_n', 'stop_force_n', 'tared_force_limit_n': "
                f"expected increasing forces, got {', '.join(map(str, forces))}"
            )
        if self.fall_in_force_n > self.touch_force_n:
            raise ValueError(
                f"key 'fall_in_force_n': expected at most 'touch_force_n' ({self.touch_force_n}),"
                f" got {self.fall_in_force_n}"
            )
        inner = self.inner_half_width_m
        if inner > 0.0 and (self.pattern != "spiral" or inner >= self.half_width_m):
            raise ValueError(
                "key 'inner_half_width_m': expected 0, or under 'half_width_m' "
                f"({self.half_width_m}) with the spiral pattern, got {inner} with {self.pattern}"
            )

    @property
    def yaw_offsets(self) -> tuple[float, ...]:
        """The passes' yaw offsets from the nominal, rad: 0, +step, -step, +2 step, -2 step,
        ... while within ``yaw_range_rad``."""
        steps = int(math.floor(self.yaw_range_rad / self.yaw_step_rad + 1e-9))
        offsets = [0.0]
        for k in range(1, steps + 1):
            offsets += [k * self.yaw_step_rad, -k * self.yaw_step_rad]
        return tuple(offsets)


AxialWeights = tuple[float, float, float, float, float, float, float, float, float]


@config_dataclass
class TouchSpiralConfig(SpiralConfig):
    """The task file's ``touch_spiral:`` section, the product's (``dipole`` and its
    variants): the blind baseline's search with the force read by touch
    (``force_reading.TactileAxialForce``), every key as ``blind:``'s, forces on the whole
    plug; ``axial_weights``: N on the plug per unit of each of the estimate's
    ``force_reading.AXIAL_TERMS`` (nine: tau_x, tau_y, tau_z in N*m, shear_x, shear_y,
    normal in N, the three torques' magnitudes). The default reads the force channel along
    T z (S's shear_y) over the sensing finger's share of the load (two alike fingers).
    ``force_window`` counts tactile frames here, and the force is their median.
    ``push_servo``: INSERT's yield to the torques while pushing (``torque_servo``);
    ``rock``: FEEL, the plug's tilt in the hand about T x found by rocking it at the first
    touch (``spiral_feel``); ``near_miss``: the sweep's near misses felt in the tilt
    torques, and retraced (``spiral_near_miss``); ``imprint_gain``: the grasp's contact
    centre on the gel read per unit of the plug's offset across the fingers (dimensionless;
    0: the offset not taken from it; controller/insertion/imprint.py)."""

    axial_weights: AxialWeights = (0.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 0.0)
    imprint_gain: float = number(0.0, 2.0, default=0.0)
    push_servo: TorqueServoSettings = TorqueServoSettings()
    rock: RockSettings = RockSettings()
    near_miss: NearMissSettings = NearMissSettings()
