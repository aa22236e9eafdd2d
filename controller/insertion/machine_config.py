"""The find-align-insert machine's (``align``) configuration: the task file's ``machine:``,
``plug:`` and ``hole:`` sections (configs/tasks/usb_c.yaml, usb_a.yaml). Every controller
reads ``signals.torque_axes`` (S on T) and the ``plug:`` and ``hole:`` sections.

Units are SI and in the key names. Tactile thresholds come in two kinds:

* **noise units** (keys ending ``_sigma``): a filtered tactile signal's departure from its
  per-run baseline divided by that channel's noise, both measured on the first
  ``signals.baseline_frames`` contact-free estimates after zeroing (``signals.py``). They do
  not depend on whether the estimate is calibrated;
* **calibrated units** (keys ``noise_floor.*``, ``limits.*_limit``, ``insert.force_budget``):
  N*m for torques, N for forces, the units of the estimate calibrated for the task's grasp
  (the task file's ``calibration:``, fitted in the scene by python -m evaluation calibrate_task;
  controller/run/task_calibration.py). A budget or limit cannot be relative. The noise
  units above are then derived from them: a channel's noise is at least its floor in N*m
  or N.

Frames: ``B`` the arm base, ``T`` the tool (TCP at the grasp point, z along the plug toward its
tip), ``S`` the tactile sensor. ``signals.torque_axes`` says which axis of T each of S's axes
is (docs/ARCHITECTURE.md, "Insertion state machine").
"""

from __future__ import annotations

import math
from dataclasses import field
from typing import Literal

import numpy as np

from controller.insertion.interface import GripperTarget
from core.config import Config, config_dataclass, number

SignedAxis = Literal["+x", "-x", "+y", "-y", "+z", "-z"]
_AXIS_INDEX = {"x": 0, "y": 1, "z": 2}
_DEG = math.pi / 180.0


@config_dataclass
class GripperSettings(Config):
    """Grasp and release. The close command targets ``close_width_m`` (below the plug's
    thickness, so the fingers stop on it) at ``close_speed_m_s`` with ``close_force_n``; the
    grasp has settled once the gripper reports holding, not moving, for ``settle_s``. Before
    closing, the fingers travel at ``preclose_speed_m_s`` to the plug's thickness plus
    ``preclose_gap_m`` (while the open gel is captured; nothing touches yet), so only that
    gap is closed slowly. Release opens to ``open_width_m`` at ``open_speed_m_s``. A re-grasp
    (slip policy ``regrasp``) first opens by ``regrasp_gap_m`` beyond the current width, then
    closes again."""

    close_width_m: float = number(0.0, 0.05, default=0.0)
    close_speed_m_s: float = number(0.001, 0.2, default=0.05)
    close_force_n: float = number(1.0, 200.0, default=40.0)
    open_width_m: float = number(0.001, 0.05, default=0.02)
    open_speed_m_s: float = number(0.001, 0.2, default=0.05)
    settle_s: float = number(0.0, 5.0, default=0.3)
    regrasp_gap_m: float = number(0.0, 0.01, default=0.0005)
    preclose_speed_m_s: float = number(0.001, 0.2, default=0.15)
    preclose_gap_m: float = number(0.0, 0.05, default=0.002)

    def preclose_target(self, plug_thickness_m: float, width_m: float) -> GripperTarget | None:
        """The fast travel to ``plug_thickness_m`` plus ``preclose_gap_m`` (m), or None when
        the fingers, ``width_m`` apart, are no wider than that already."""
        preclose_m = plug_thickness_m + self.preclose_gap_m
        if width_m <= preclose_m:
            return None
        return GripperTarget(preclose_m, self.preclose_speed_m_s, self.close_force_n)

    def close_target(self) -> GripperTarget:
        """The close command (``close_*``)."""
        return GripperTarget(self.close_width_m, self.close_speed_m_s, self.close_force_n)

    def open_target(self, width_m: float) -> GripperTarget:
        """The open command to ``width_m`` (m) at ``open_speed_m_s``."""
        return GripperTarget(width_m, self.open_speed_m_s, self.close_force_n)


@config_dataclass
class NoiseFloor(Config):
    """Lowest noise level each channel is credited with, in calibrated units, so a quiet
    (simulated) signal does not make every departure infinitely significant: ``tilt_x``
    (tau_x), ``tilt_y`` (tau_y), ``inplane`` (tau_z), in N*m; ``shear_x``, ``shear_y``,
    ``normal``, in N. The defaults are the USB-C task's."""

    tilt_x: float = number(1e-9, 1e3, default=0.0008662)
    tilt_y: float = number(1e-9, 1e3, default=0.0005886)
    inplane: float = number(1e-9, 1e3, default=0.0005)
    shear_x: float = number(1e-9, 1e3, default=0.004923)
    shear_y: float = number(1e-9, 1e3, default=0.00533)
    normal: float = number(1e-9, 1e3, default=0.03795)


@config_dataclass
class SignalSettings(Config):
    """How the tactile estimate becomes the machine's signals.

    ``zeroing_frames``: frames the loop averages into the new reference when the machine asks
    for a re-zero (``TactileEstimator.rezero``). ``baseline_frames``: contact-free estimates
    after zeroing from which each channel's mean (subtracted) and noise (standard deviation,
    at least its ``noise_floor``) are measured. ``ema_alpha``: weight of a new estimate in the
    exponential moving average of every normalised channel (1: no filtering). ``torque_axes``:
    which signed axis of T each of S's x, y, z axes is (a proper rotation); default: image
    columns along the plug's width (T x), image rows down toward the fingertips (T z), so the
    camera's axis S z is -T y.
    """

    zeroing_frames: int = number(1, 100, default=5)
    baseline_frames: int = number(2, 200, default=10)
    ema_alpha: float = number(0.01, 1.0, default=0.4)
    noise_floor: NoiseFloor = field(default_factory=NoiseFloor)
    torque_axes: tuple[SignedAxis, SignedAxis, SignedAxis] = ("+x", "+z", "-y")

    def __post_init__(self) -> None:
        try:
            s2t_matrix(self.torque_axes)
        except ValueError as exc:
            raise ValueError(f"key 'torque_axes': {exc}") from None


@config_dataclass
class ApproachSettings(Config):
    """APPROACH: move the tip to ``height_m`` above the nominal opening (``touched_height_m``
    above the board surface once touch has found it) with the plug tilted by
    ``tilt_rad`` about T's ``tilt_axis`` (the paper's tilted approach), moving at up to
    ``move_speed_m_s`` / ``rotate_speed_rad_s`` until within ``pose_tol_m`` / ``angle_tol_rad``;
    the position and orientation servo of every phase has the gain ``pose_gain_1_s`` (speed
    = gain x error, bounded). Then descend at ``descend_speed_m_s`` until contact: the norm
    of the normalised signals at least ``contact_sigma`` for ``contact_frames`` successive
    estimates. A tip more than
    ``overtravel_m`` below the board surface without contact: limit exceeded."""

    height_m: float = number(0.0, 0.1, default=0.003)
    touched_height_m: float = number(0.0, 0.1, default=0.001)
    tilt_rad: float = number(-45 * _DEG, 45 * _DEG, default=15 * _DEG)
    tilt_axis: Literal["x", "y"] = "x"
    move_speed_m_s: float = number(1e-4, 0.25, default=0.045)
    rotate_speed_rad_s: float = number(1e-3, 2.0, default=0.5)
    descend_speed_m_s: float = number(1e-4, 0.05, default=0.002)
    pose_gain_1_s: float = number(0.1, 50.0, default=4.0)
    pose_tol_m: float = number(1e-5, 0.01, default=0.0003)
    angle_tol_rad: float = number(1e-4, 0.2, default=0.5 * _DEG)
    overtravel_m: float = number(0.0, 0.05, default=0.004)
    contact_sigma: float = number(0.5, 1e4, default=8.0)
    contact_frames: int = number(1, 100, default=3)


@config_dataclass
class FeelSettings(Config):
    """FEEL, at the run's first touch (phases/feel.py), when ``enabled`` (off by default:
    on the tuning seeds it has not yet paid for its time, docs/BENCHMARKS.md, "The plug in
    the hand by touch"): APPROACH brings the tip down
    ``offset_m`` from the nominal opening along its narrow axis (beyond the opening's
    uncertainty, so the tip's face lands on the board); the tip is held ``press_depth_m``
    below its height at contact for ``settle_s``; then the TCP turns about the horizontal
    axis across the opening's width at ``rock_speed_rad_s``, toward the side that makes the
    in-plane torque (about T y) smaller, until that torque changes sign with at least
    ``flip_sigma`` (noise units) on the new side; then back until it changes sign again.
    No change within ``rock_max_rad`` of the starting rotation: the turn is reversed once,
    then FEEL ends without an estimate (the nominal grasp is kept)."""

    enabled: bool = False
    offset_m: float = number(0.0, 0.05, default=0.0065)
    press_depth_m: float = number(0.0, 0.005, default=0.0005)
    settle_s: float = number(0.0, 5.0, default=0.3)
    rock_speed_rad_s: float = number(0.005, 1.0, default=0.2)
    rock_max_rad: float = number(0.01, 0.5, default=0.14)
    flip_sigma: float = number(0.0, 100.0, default=1.0)


@config_dataclass
class SearchSettings(Config):
    """SEARCH: drag the tilted tip over the board along ``pattern`` (``spiral``: Archimedean,
    ``pitch_m`` between turns; ``raster``: lines ``pitch_m`` apart along the hole's width
    axis) at ``speed_m_s``, centred on the nominal opening and bounded by the pose
    uncertainty ``uncertainty_xy_m`` (half-width of the square searched; the spiral's radius
    reaches its corner) and ``uncertainty_yaw_rad`` (corrected by ALIGN's in-plane servo).
    The TCP is held ``press_depth_m`` below the height where contact was found (a preload
    into the compliant wrist). When a pattern is exhausted it starts again.

    Hole found: the *drag resistance* r (the normalised torque's component about the axis
    z_T x d, d the drag direction in B: the torque an edge catching the tip produces) rises
    by max(``hole_rise_sigma``, ``hole_rise_ratio`` x |expected|) above the expected
    resistance for ``hole_frames`` successive estimates. Expected: the present load (the
    normalised axial force, at least 1) times the slow average (weight ``reference_alpha``)
    of r / load, since friction grows with the load (the drag direction is filtered like
    the signals, so their lags match). For the first ``settle_s`` of SEARCH (the preload
    building up) the average is only learned, with the signals' ``ema_alpha``. Contact lost:
    the signal norm below ``contact_lost_sigma`` for ``contact_lost_frames`` successive
    estimates: the tip then probes straight down at the approach's descent speed; contact
    again with the tip ``in_hole_depth_m`` below the surface is the hole found (the plug fell
    into the opening); contact above that resumes the search; no contact down to the
    approach's ``overtravel_m``: contact lost.
    Hole found, too: the *load drop*. The TCP's height is held, so when the tip drops into
    the opening the wrist's z spring relaxes and the axial force (normalised) falls: below
    (1 - ``hole_drop_ratio``) times its reference, and by at least ``hole_drop_sigma``, for
    ``hole_frames`` successive estimates (any drag direction). The reference is learned like
    the resistance's (the first ``settle_s``, weight ``ema_alpha``), then followed with
    ``reference_alpha`` while the load is not dropping. ``hole_drop_ratio`` 0 turns the rule
    off.
    ``in_hole_depth_m``: a tip in contact this far below the board surface is in the opening
    (used when autonomy resumes after TELEOP or ESTOP: ALIGN rather than SEARCH).
    Out of time (``timeouts.search_s``) without finding the hole: BACKOFF and SEARCH again
    (``search_timeout``, a retry), and from then on each pass of the pattern (its whole
    length, out or back) turns the plug about B's z by the next of +``retry_yaw_rad``,
    -``retry_yaw_rad`` and 0 from the approach's yaw: a tilted plug's long leading edge
    drops into the opening only when it lies within the opening's width, so a search that
    never caught at the nominal yaw is not repeated at it.
    The drag: the tip follows the pattern at ``speed_m_s`` plus the servo toward it, at most
    ``max_speed_ratio`` x ``speed_m_s``; a gap between ticks longer than ``max_tick_s``
    advances the path by that time only. The drag resistance is judged only while dragging
    steadily (the filtered drag direction's speed at least ``steady_speed_ratio`` x
    ``speed_m_s`` and its cosine to the latest command at least ``steady_cosine``), and
    divided by a load of at least ``min_load_sigma`` (noise units; SEARCH's load handed to
    ALIGN and INSERT is at least that too)."""

    pattern: Literal["spiral", "raster"] = "spiral"
    pitch_m: float = number(1e-4, 0.01, default=0.0008)
    speed_m_s: float = number(1e-4, 0.05, default=0.004)
    uncertainty_xy_m: float = number(0.0, 0.05, default=0.003)
    uncertainty_yaw_rad: float = number(0.0, 0.5, default=3 * _DEG)
    press_depth_m: float = number(0.0, 0.01, default=0.0003)
    hole_rise_sigma: float = number(0.5, 1e4, default=10.0)
    hole_rise_ratio: float = number(0.0, 100.0, default=1.0)
    hole_frames: int = number(1, 100, default=3)
    hole_drop_ratio: float = number(0.0, 1.0, default=0.4)
    hole_drop_sigma: float = number(0.0, 1e4, default=4.0)
    reference_alpha: float = number(0.001, 1.0, default=0.05)
    settle_s: float = number(0.0, 10.0, default=0.5)
    contact_lost_sigma: float = number(0.0, 1e4, default=3.0)
    contact_lost_frames: int = number(1, 1000, default=15)
    in_hole_depth_m: float = number(0.0, 0.01, default=0.0005)
    retry_yaw_rad: float = number(0.0, 0.5, default=0.035)
    max_speed_ratio: float = number(1.0, 10.0, default=2.0)
    max_tick_s: float = number(0.001, 10.0, default=0.1)
    steady_speed_ratio: float = number(0.0, 1.0, default=0.5)
    steady_cosine: float = number(0.0, 1.0, default=0.95)
    min_load_sigma: float = number(0.01, 1e4, default=1.0)


@config_dataclass
class AlignSettings(Config):
    """ALIGN, after SEARCH caught the tilted tip's lowest edge (the heel) in the opening, in
    three stages (docs/ARCHITECTURE.md, "ALIGN"):

    *Seek*: move the heel horizontally against the tilt's lean at ``seek_speed_m_s``,
    pressing with SEARCH's load, until the opening's wall (or the friction at the rim)
    holds it: the lateral resistance r (``search.lateral_resistance``: the tilt torque
    of a force against the motion, noise units) risen by ``wall_sigma`` above its value when
    ALIGN began, for ``frames`` successive estimates. No wall within ``seek_max_m``: the
    catch was not the opening (BACKOFF, then SEARCH again). While seeking and turning, the
    plug yields in yaw (about T z) to the torque about its axis: w_Tz = -``heel_yaw_gain``
    x n (n that torque in T z, normalised, no tolerance): with the heel in the opening and
    the plug yawed, the opening's long walls twist it back.

    *Turn*: turn the TCP toward straight down about the heel at ``upright_gain_1_s`` x the
    tilt (capped by ``max_turn_speed_rad_s``), holding the heel against the wall: its
    horizontal speed is ``seek_speed_m_s`` x (1 - rise / ``wall_sigma``) within +-1. Ends
    when the tilt of T z from straight down is within ``tilt_tol_rad`` (the arm's upright,
    which is the plug's only for a nominal grasp). If the tip face's lowest edge is then
    ``enter_m`` below the surface found by touch, the plug is in the opening (the servo
    stage); otherwise the *width* stage first, then the *yaw* stage. That depth assumes the
    nominal grasp: a plug standing on the rim with one end in the opening can read
    entered. So after two jams at one height at a catch (INSERT's push; the second no
    deeper by ``enter_m``) the plug is in the opening only ``enter_m`` below where it
    jammed, too.

    *Width*: an in-grasp tilt about T y leaves one end of the plug's tip low: that corner
    catches in the opening with the plug's centre off toward the other end, and the
    in-plane torque's sign names the side (tau_z > 0: the centre is toward +T x; it names
    none below ``width_sigma`` noise units, and the stage is skipped). The tip
    slides along T x toward the low end at ``width_speed_m_s``, pressing, until the plug
    enters (the servo stage); the end wall holding it (the lateral resistance risen by
    ``wall_sigma`` for ``frames`` estimates) or ``width_max_m`` slid without entering: the
    yaw stage. ``width_speed_m_s`` 0 skips the stage.

    *Yaw*: sweep the yaw as INSERT's press does (``insert.yaw_sweep_rad``,
    ``yaw_rate_rad_s``, ``sweeps``) until the plug enters; back where the sweep began, a
    plug at least ``entering_ratio`` x ``enter_m`` in goes on to the servo, any other backs
    off to SEARCH again. The opening's long walls holding the plug's yaw also end the sweep (the
    servo stage): the torque about the plug's axis at least ``twist_sigma`` noise units
    for ``frames`` estimates (the plug is in the slot even where the depth by touch says
    otherwise: the in-grasp pose is unknown); 0 turns this off.

    *Servo*: turn about the tip to null the torques, pressing: the TCP
    yields to the contact's torque, w_T = -R_S2T (k * n_S) (n_S the normalised filtered
    torques tau_x, tau_y, tau_z, zero within their tolerance; gains ``gain_tau_*`` in rad/s
    per noise unit). Aligned: every torque within its tolerance (``tol_tau_*_sigma``, noise
    units) with the axial load at least ``aligned_load_ratio`` x SEARCH's, for ``frames``
    successive estimates, or the plug down to ``insert.depth_m`` (it slid in while turning). The
    servo (and INSERT's share of it) never tilts the TCP beyond ``servo_tilt_max_rad`` from
    straight down (the in-grasp tilt, the board's and a margin; below
    ``limits.tilt_limit_rad``): past it, only its uprighting part is kept. The turn's and
    the servo's rate (rad/s) is capped by ``max_turn_speed_rad_s``."""

    heel_yaw_gain: float = number(0.0, 10.0, default=0.02)
    gain_tau_x: float = number(0.0, 10.0, default=0.02)
    gain_tau_y: float = number(0.0, 10.0, default=0.02)
    gain_tau_z: float = number(0.0, 10.0, default=0.02)
    tol_tau_x_sigma: float = number(0.1, 1e4, default=4.0)
    tol_tau_y_sigma: float = number(0.1, 1e4, default=4.0)
    tol_tau_z_sigma: float = number(0.1, 1e4, default=4.0)
    upright_gain_1_s: float = number(0.0, 20.0, default=3.0)
    tilt_tol_rad: float = number(1e-4, 0.2, default=1 * _DEG)
    max_turn_speed_rad_s: float = number(1e-3, 1.0, default=0.2)
    frames: int = number(1, 100, default=3)
    seek_speed_m_s: float = number(1e-5, 0.02, default=0.001)
    seek_max_m: float = number(1e-5, 0.01, default=0.0025)
    wall_sigma: float = number(0.1, 1e4, default=2.0)
    enter_m: float = number(1e-5, 0.01, default=0.001)
    width_speed_m_s: float = number(0.0, 0.02, default=0.001)
    width_max_m: float = number(1e-5, 0.01, default=0.004)
    width_sigma: float = number(0.0, 1e4, default=1.0)
    servo_tilt_max_rad: float = number(0.0, 1.0, default=10 * _DEG)
    twist_sigma: float = number(0.0, 1e4, default=6.0)
    entering_ratio: float = number(0.0, 1.0, default=0.5)
    aligned_load_ratio: float = number(0.0, 10.0, default=0.5)


@config_dataclass
class InsertSettings(Config):
    """INSERT, in two stages.

    *Press*: move the tip down (B's -z) at ``speed_m_s`` times the axial load's shortfall
    below ``press_load_ratio`` x SEARCH's load reference (within +-1), so a plug standing on
    the opening's rim is pressed with a bounded force instead of compressing the wrist. Once
    that load is reached (the *stall height*: the TCP's height then), the TCP sweeps the
    plug's yaw about its tip axis, a triangle wave between +-``yaw_sweep_rad`` about the
    opening's nominal yaw at ``yaw_rate_rad_s`` (the opening's yaw is uncertain and the
    USB-C clearances leave about 1 deg); the stall height is taken once the load is at
    least ``stall_load_ratio`` x the press load. The TCP ``engage_m`` below the stall height,
    or the load below ``give_way_ratio`` x the press load after the stall (the load gave
    way: the plug entered the opening) begins the push; ``sweeps`` whole sweeps
    without engaging: the plug is not over the opening (BACKOFF, then APPROACH and SEARCH
    again where the pattern left off).

    *Push*: the tip straight down at ``speed_m_s``, the yaw held, ALIGN's torque servo at
    ``compliance_scale`` of its gains. The axial force (the estimated force along T z,
    estimate units) above ``force_budget``, or the tilt torque (norm of the normalised
    torques about T x and T y) risen by ``jam_rise_sigma`` above its lowest value in this
    INSERT, for ``jam_frames`` successive estimates, or the TCP not ``progress_m`` lower for
    ``stall_s``: a jam (BACKOFF, then ALIGN).
    ``force_budget`` in N.

    Success (either stage): the tip ``depth_m`` below the board surface, by the arm's TCP,
    with the axial load below the press load (so a compressed wrist is not taken for
    depth)."""

    speed_m_s: float = number(1e-4, 0.05, default=0.004)
    depth_m: float = number(1e-4, 0.05, default=0.005)
    compliance_scale: float = number(0.0, 1.0, default=0.5)
    force_budget: float = number(1e-6, 1e4, default=1.333)
    jam_rise_sigma: float = number(0.5, 1e4, default=15.0)
    jam_frames: int = number(1, 100, default=3)
    press_load_ratio: float = number(0.1, 100.0, default=1.0)
    engage_m: float = number(1e-5, 0.01, default=0.0008)
    yaw_sweep_rad: float = number(0.0, 0.5, default=0.07)
    yaw_rate_rad_s: float = number(1e-3, 1.0, default=0.25)
    sweeps: int = number(1, 20, default=1)
    stall_s: float = number(0.1, 60.0, default=1.5)
    progress_m: float = number(1e-6, 0.01, default=1e-4)
    stall_load_ratio: float = number(0.0, 1.0, default=0.8)
    give_way_ratio: float = number(0.0, 1.0, default=0.5)


@config_dataclass
class BackoffSettings(Config):
    """BACKOFF: lift the tip ``distance_m`` at ``speed_m_s``, then ALIGN again (after a jam)
    or APPROACH and SEARCH again (after a press that never engaged, a catch that was not the
    opening or an ALIGN timeout; then only once the tip's lowest edge is also ``distance_m``
    above the surface found). More than
    ``max_retries`` back-offs and re-grasps in one run: too many retries."""

    distance_m: float = number(1e-5, 0.02, default=0.001)
    speed_m_s: float = number(1e-4, 0.05, default=0.004)
    max_retries: int = number(0, 100, default=10)


@config_dataclass
class ReleaseSettings(Config):
    """RELEASE opens the gripper and waits until it stops (at least ``settle_s``); RETRACT
    lifts the TCP ``retract_distance_m`` at ``retract_speed_m_s``."""

    settle_s: float = number(0.0, 5.0, default=0.2)
    retract_distance_m: float = number(0.0, 0.2, default=0.03)
    retract_speed_m_s: float = number(1e-4, 0.25, default=0.03)


@config_dataclass
class SlipSettings(Config):
    """What a slip does: ``trigger`` ``gross`` (the estimate's ``slip_gross``) or ``suspected``
    (also incipient slip), or the gripper no longer holding. ``policy`` ``regrasp``: lift the
    tip ``lift_m`` clear of the board, re-grasp, re-zero and approach again (a retry);
    ``fail``: FAILED (slip)."""

    policy: Literal["regrasp", "fail"] = "regrasp"
    trigger: Literal["gross", "suspected"] = "gross"
    lift_m: float = number(0.0, 0.05, default=0.005)


@config_dataclass
class Limits(Config):
    """The machine's own limits. Exceeded -> FAILED (limit exceeded): the tactile limits, in
    calibrated units on the baseline-subtracted estimate, ``tilt_torque_limit`` (|tau_x|,
    |tau_y|, N*m), ``inplane_torque_limit`` (|tau_z|, N*m), ``force_limit`` (axial force,
    N); ``tilt_limit_rad``, the TCP's tilt from straight down (rad; below the loop's and the
    arm's ``max_tilt_rad``, or it could never trip: controller/limit_checks.py). Every
    command the machine makes (the operator's under TELEOP too) has its twist's norms capped
    at ``max_command_speed_m_s`` (m/s) and ``max_command_angular_speed_rad_s`` (rad/s); the
    loop's safety limits (``limits:``) bound it again."""

    tilt_torque_limit: float = number(1e-6, 1e4, default=0.2166)
    inplane_torque_limit: float = number(1e-6, 1e6, default=0.05702)
    force_limit: float = number(1e-6, 1e4, default=5.33)
    tilt_limit_rad: float = number(1 * _DEG, 60 * _DEG, default=0.30)
    max_command_speed_m_s: float = number(1e-4, 0.5, default=0.05)
    max_command_angular_speed_rad_s: float = number(1e-3, 3.0, default=0.6)


@config_dataclass
class Timeouts(Config):
    """Longest time in each autonomous phase, and in all of them together (time under TELEOP
    or ESTOP does not count): exceeded -> FAILED (timeout); ``align_s`` or ``search_s``
    exceeded -> BACKOFF (``align_timeout``, ``search_timeout``) and SEARCH again, a retry
    (SearchSettings: a search retried for time turns its passes to other yaws)."""

    grasp_s: float = number(0.1, 600.0, default=5.0)
    approach_s: float = number(0.1, 600.0, default=10.0)
    feel_s: float = number(0.1, 600.0, default=8.0)
    search_s: float = number(0.1, 600.0, default=30.0)
    align_s: float = number(0.1, 600.0, default=10.0)
    insert_s: float = number(0.1, 600.0, default=8.0)
    backoff_s: float = number(0.1, 600.0, default=3.0)
    release_s: float = number(0.1, 600.0, default=3.0)
    retract_s: float = number(0.1, 600.0, default=5.0)
    total_s: float = number(1.0, 3600.0, default=90.0)


@config_dataclass
class MachineConfig(Config):
    """The insertion machine (task file ``machine:``); see each part's docstring."""

    gripper: GripperSettings = field(default_factory=GripperSettings)
    signals: SignalSettings = field(default_factory=SignalSettings)
    approach: ApproachSettings = field(default_factory=ApproachSettings)
    feel: FeelSettings = field(default_factory=FeelSettings)
    search: SearchSettings = field(default_factory=SearchSettings)
    align: AlignSettings = field(default_factory=AlignSettings)
    insert: InsertSettings = field(default_factory=InsertSettings)
    backoff: BackoffSettings = field(default_factory=BackoffSettings)
    release: ReleaseSettings = field(default_factory=ReleaseSettings)
    slip: SlipSettings = field(default_factory=SlipSettings)
    limits: Limits = field(default_factory=Limits)
    timeouts: Timeouts = field(default_factory=Timeouts)

    def __post_init__(self) -> None:
        tilts = (("approach.tilt_rad", self.approach.tilt_rad),
                 ("align.servo_tilt_max_rad", self.align.servo_tilt_max_rad))  # fmt: skip
        for key, tilt in tilts:  # under the trip, or it could never trip
            if abs(tilt) >= self.limits.tilt_limit_rad:
                raise ValueError(
                    f"key '{key}': expected less than limits.tilt_limit_rad "
                    f"({self.limits.tilt_limit_rad}) in magnitude, got {tilt}"
                )
        if self.insert.force_budget > self.limits.force_limit:
            raise ValueError(
                f"key 'insert.force_budget': expected at most limits.force_limit "
                f"({self.limits.force_limit}), got {self.insert.force_budget}"
            )
        if self.search.contact_lost_sigma >= self.approach.contact_sigma:
            raise ValueError(
                f"key 'search.contact_lost_sigma': expected below approach.contact_sigma "
                f"({self.approach.contact_sigma}), got {self.search.contact_lost_sigma}"
            )


def s2t_matrix(axes: tuple[str, str, str]) -> np.ndarray:
    """The rotation R_S2T (3x3, columns: S's axes in T) for signed tool axes such as
    ``("+x", "+z", "-y")``; ValueError unless they form a proper rotation."""
    matrix = np.zeros((3, 3))
    for column, name in enumerate(axes):
        if len(name) != 2 or name[0] not in "+-" or name[1] not in _AXIS_INDEX:
            raise ValueError(f"expected signed axes like '+x', got {name!r}")
        matrix[_AXIS_INDEX[name[1]], column] = 1.0 if name[0] == "+" else -1.0
    if not np.allclose(matrix @ matrix.T, np.eye(3)) or np.linalg.det(matrix) < 0:
        raise ValueError(f"expected each tool axis once and a right-handed frame, got {list(axes)}")
    return matrix
