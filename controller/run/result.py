"""The outcome of one insertion trial: on the robot, the machine's own (no truth: the true
forces are NaN); in simulation, scored against the simulator's truth (evaluation/trials/),
as the batch tools collect it."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict, dataclass, fields
from typing import Any, Literal, get_args

TrialStatus = Literal["inserted", "failed", "error"]
"""How a trial ended: ``inserted`` (the plug reached the depth and the machine ended in DONE),
``failed`` (it ran to another outcome) or ``error`` (it raised, or its worker was lost, before
any outcome: no simulated time, no force measured)."""

STATUSES: tuple[TrialStatus, ...] = get_args(TrialStatus)


@dataclass(frozen=True)
class TrialResult:
    """One trial's outcome.

    ``task``: the task name (usb_a, usb_c); ``controller``: the controller's name (dipole,
    fingervision, align, blind, oracle, ...: controller/run/controllers.py); ``seed``: the
    scene's seed; ``success``: the plug at the depth at the end and the machine in DONE;
    ``status``: how the trial ended (``TrialStatus``; ``inserted`` exactly when
    ``success``); ``failure_reason``: the FAILED transition's reason, or the error's (None on
    success); ``time_to_insert_s``: simulated time from the controller's first tick (the
    devices' start-up, such as the gripper's activation, comes before it) to reaching the
    depth for good (the last arrival, from which the plug stays at depth to the end; None
    when it never did); ``duration_s``: simulated time of the whole run;
    ``max_wrist_force_n``: the largest true force of the compliant wrist's springs (ground
    truth, N); ``force_limit_n``: the task's limit on it;
    ``wall_time_s``: the wall-clock time the trial took; ``max_contact_force_n`` and
    ``p99_contact_force_n``: the largest and the 99th percentile of the plug's true contact
    force with the board and the receptacle (the sum of the contacts' normal forces, N,
    peak per truth row: a wedged plug's squeeze counts once per wall);
    ``max_insertion_force_n`` and ``p99_insertion_force_n``: the same of the insertion force
    (the net contact force on the plug along the hole's axis, N);
    ``contact_force_limit_n``: the task's limit on the insertion force (the connector's
    specified insertion force); ``insertion_force_violations``: how many times the insertion
    force rose above that limit (a violation fails the trial: ``insertion_force_exceeded``).

    The plug's pose in the hand (controller/insertion/grasp_estimate.py; NaN where unknown):
    ``grasp_tilt_est_rad`` the machine's estimate of its tilt in the width plane (about T y)
    and ``grasp_tilt_true_rad`` the scene's; ``grasp_tilt_thickness_true_rad`` the true tilt
    in the thickness plane (about T x), ``thickness_tilt_to_receptacle_true_rad`` the same
    from the receptacle's axis (the board's normal; the board tilts), which FEEL's flat angle
    measures, ``width_tilt_to_receptacle_true_rad`` the width plane's tilt from that axis,
    ``grasp_tilt_thickness_est_rad`` the press spiral's
    estimate of it (its FEEL's flat angle; nan without one); ``tip_x_est_m`` the estimated tip's
    offset along T x from the nominal (the width-plane estimate's: for the press spiral with
    the plug's offset across the fingers from its imprint, ``tip_x_estimate_m``),
    ``tip_y_est_m`` along T y
    (the thickness-plane estimate's, ``SpiralMachine.tip_y_estimate_m``: the plug's length
    times the sine of the tilt; nan without one), and ``tip_x_true_m``, ``tip_y_true_m`` the
    true tip's along T x and T y (m); ``imprint_offset_est_m`` the plug's offset across the
    fingers (along T x) that the press spiral last took from the grasp's imprint (m; nan
    unread) and ``imprint_true_m`` the truth it stands for, where the plug's axis crosses
    the gel's centre row (m along T x, controller/insertion/imprint.py).

    The torques the opening's walls put on the plug as it goes in (the scene's truth,
    evaluation/trials/entry_torque.py; nan when the tip never got 1 mm into the opening):
    ``entry_tilt_torque_rms_nm`` the RMS of the tilt torque (about S x and S y) and
    ``entry_inplane_torque_rms_nm`` of the in-plane torque (about S z, the gel's normal),
    N*m, each the change at the gel from the plug's hold in the air.
    """

    task: str
    controller: str
    seed: int
    success: bool
    status: TrialStatus
    failure_reason: str | None
    time_to_insert_s: float | None
    duration_s: float
    max_wrist_force_n: float
    force_limit_n: float
    wall_time_s: float
    max_contact_force_n: float = 0.0
    p99_contact_force_n: float = 0.0
    max_insertion_force_n: float = 0.0
    p99_insertion_force_n: float = 0.0
    contact_force_limit_n: float = float("nan")
    insertion_force_violations: int = 0
    grasp_tilt_est_rad: float = float("nan")
    grasp_tilt_true_rad: float = float("nan")
    grasp_tilt_thickness_true_rad: float = float("nan")
    grasp_tilt_thickness_est_rad: float = float("nan")
    thickness_tilt_to_receptacle_true_rad: float = float("nan")
    width_tilt_to_receptacle_true_rad: float = float("nan")
    tip_x_est_m: float = float("nan")
    tip_x_true_m: float = float("nan")
    tip_y_est_m: float = float("nan")
    tip_y_true_m: float = float("nan")
    imprint_offset_est_m: float = float("nan")
    imprint_true_m: float = float("nan")
    entry_tilt_torque_rms_nm: float = float("nan")
    entry_inplane_torque_rms_nm: float = float("nan")

    def __post_init__(self) -> None:
        if self.status not in STATUSES:
            raise ValueError(f"status {self.status!r}: expected one of {', '.join(STATUSES)}")
        if self.success != (self.status == "inserted"):
            raise ValueError(f"status {self.status!r} contradicts success={self.success}")

    def as_row(self) -> dict[str, Any]:
        """The result as a flat dict (one CSV row)."""
        return asdict(self)

    @classmethod
    def from_row(cls, row: Mapping[str, str]) -> TrialResult:
        """The result of one ``trials.csv`` row (``as_row`` written by the batch: an empty
        cell is None, floats as ``repr``); ValueError (or KeyError) on a malformed row."""
        values: dict[str, Any] = {}
        for f in fields(cls):
            name = f.name
            if name not in row and name in LATER_FIELDS:  # a table from before they existed
                continue
            text = row[name]
            if name == "failure_reason":
                values[name] = text or None
            elif name in _TEXT_FIELDS:
                values[name] = text
            elif name in _INT_FIELDS:
                values[name] = int(text)
            elif name == "success":
                if text not in ("True", "False"):
                    raise ValueError(f"success {text!r}: expected True or False")
                values[name] = text == "True"
            else:
                values[name] = None if text == "" and name == "time_to_insert_s" else float(text)
        return cls(**values)


_TEXT_FIELDS = ("task", "controller", "status")
_INT_FIELDS = ("seed", "insertion_force_violations")
POSE_FIELDS = (
    "grasp_tilt_est_rad",
    "grasp_tilt_true_rad",
    "grasp_tilt_thickness_true_rad",
    "grasp_tilt_thickness_est_rad",
    "thickness_tilt_to_receptacle_true_rad",
    "width_tilt_to_receptacle_true_rad",
    "tip_x_est_m",
    "tip_x_true_m",
    "tip_y_est_m",
    "tip_y_true_m",
    "imprint_offset_est_m",
    "imprint_true_m",
)
ENTRY_FIELDS = ("entry_tilt_torque_rms_nm", "entry_inplane_torque_rms_nm")
#: the columns a table written before them may lack (they read as unknown)
LATER_FIELDS = POSE_FIELDS + ENTRY_FIELDS
