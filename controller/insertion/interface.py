"""What the insertion state machine takes and gives each tick, and its phases.

The machine is pure (no I/O): the control loop (``controller.loop``) reads the devices, builds
an ``Observation`` and calls ``step(observation) -> Command``; the loop then clamps the command
(``controller.safety``) and sends it. Frames (docs/ARCHITECTURE.md): ``B`` the arm base, ``T``
the tool (TCP at the stick's grasp point), ``S`` the tactile sensor; SI units throughout.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum
from typing import Literal, Protocol

from controller.tactile.wrench import WrenchEstimate
from core.devices import ArmStatus, GripperStatus, Pose, Twist


class Phase(Enum):
    """The machine's states. DONE and FAILED are terminal; TELEOP and ESTOP are overrides."""

    GRASP = "grasp"
    APPROACH = "approach"
    FEEL = "feel"  # the first touch: the plug's pose in the hand, by rocking on the board
    SEARCH = "search"
    ALIGN = "align"
    INSERT = "insert"
    BACKOFF = "backoff"  # jam detected during INSERT: lift a little, then ALIGN again
    RELEASE = "release"
    RETRACT = "retract"
    DONE = "done"
    FAILED = "failed"
    TELEOP = "teleop"
    ESTOP = "estop"


class FailureReason(Enum):
    """Why a run ended in FAILED (``Transition.reason`` names it)."""

    TIMEOUT = "timeout"
    LIMIT_EXCEEDED = "limit_exceeded"
    SLIP = "slip"
    CONTACT_LOST = "contact_lost"
    TOO_MANY_RETRIES = "too_many_retries"
    DEVICE_FAULT = "device_fault"


@dataclass(frozen=True)
class TeleopInput:
    """The gamepad's arbitration state for one tick (``controller.teleop`` builds it).

    ``connected``: the pad is attached. ``in_control``: the operator holds control (a stick
    moved past the dead zone since the last hand-back). ``twist``: the operator's TCP twist
    in B, zero unless in control. ``gripper_open`` / ``gripper_close``: the gripper buttons
    this tick. ``hand_back``: the hand-back button was pressed this tick. ``estop``: the
    e-stop button is held; ``estop_ack``: the acknowledge button was pressed this tick.
    ``deadman``: the deadman button is held (for display and the record; the arbiter has
    already zeroed the twist without it when the task requires it).
    """

    connected: bool = False
    in_control: bool = False
    twist: Twist = field(default_factory=Twist)
    gripper_open: bool = False
    gripper_close: bool = False
    hand_back: bool = False
    estop: bool = False
    estop_ack: bool = False
    deadman: bool = False


@dataclass(frozen=True)
class Observation:
    """Everything the machine may know at one tick. ``wrench`` is the tactile estimate of the
    newest frame (None before the first frame is processed); ``fault`` names a device or
    watchdog fault the loop detected this tick (None: none); ``contact_centre_s_m``: where
    the grasp presses the gel (x, y in S, m), measured against the open gel when the
    estimator last took its reference (None: not measured)."""

    t_s: float
    wrench: WrenchEstimate | None
    arm: ArmStatus
    gripper: GripperStatus
    teleop: TeleopInput
    fault: str | None = None
    contact_centre_s_m: tuple[float, float] | None = None


@dataclass(frozen=True)
class GripperTarget:
    """A gripper command: finger opening in m, speed in m/s, force in N."""

    width_m: float
    speed_m_s: float
    force_n: float


@dataclass(frozen=True)
class Command:
    """One tick's output. At most one of ``twist`` (TCP velocity in B, held for the loop's
    command duration) and ``pose`` (servo target of T in B); neither: hold still.
    ``gripper``: a new gripper target, or None to leave it. ``capture_open_tactile``: the
    loop has the estimator take the next frames as the open gel (fingers open, nothing
    touching: before a grasp), against which the grasp's contact is measured.
    ``rezero_tactile``: the loop re-zeroes the estimator's reference from the next frames
    (after a grasp or a re-grasp). ``rule``: the machine's rule that decided this command,
    ``phase.rule`` (e.g. ``search.drag``, ``search.torque_catch``, ``align.torque_servo``;
    docs/ARCHITECTURE.md lists them), recorded with every tick; empty when the machine names
    none. ``stage``: the sub-stage in which that rule was decided, ``phase.stage`` (e.g.
    ``align.seek``; the phase modules' enums, listed in definition.py), recorded with every
    tick; empty when the machine has no sub-stages.
    """

    twist: Twist | None = None
    pose: Pose | None = None
    gripper: GripperTarget | None = None
    capture_open_tactile: bool = False
    rezero_tactile: bool = False
    rule: str = ""
    stage: str = ""

    def __post_init__(self) -> None:
        if self.twist is not None and self.pose is not None:
            raise ValueError("Command: expected a twist or a pose target, not both")


@dataclass(frozen=True)
class Transition:
    """A phase change at ``t_s``, with its reason (the guard: a FailureReason's value for
    FAILED) and the ``rule`` that fired it where a guard has several (``hole_found``:
    ``torque_catch``, ``load_drop`` or both joined by ``+``, or ``probe``; else empty)."""

    t_s: float
    source: Phase
    target: Phase
    reason: str
    rule: str = ""


GraspPlane = Literal["thickness", "width"]
"""The plane of an in-hand tilt: ``thickness`` about T x (the tip moves along T y), ``width``
about T y (the tip moves along T x)."""


@dataclass(frozen=True)
class InHandEstimate:
    """An estimate of the plug's pose in the hand a machine made at ``t_s`` (s, the loop's
    clock): its tilt ``tilt_rad`` in ``plane`` (rad, the TCP turn that sets the plug upright
    in that plane: about T x for ``thickness``, about T y for ``width``), the tip's offset
    ``tip_offset_m`` from the nominal it implies (m, along T y for ``thickness``, along T x
    for ``width``), ``method`` how it was found (``rock``: rocking the pressed tip until its
    face lies flat; ``imprint``: the grasp's contact centre on the gel, which gives the tip's
    offset along T x only, ``tilt_rad`` NaN) and ``kept`` whether it passed its checks (a
    kept estimate is the one the machine acts on; one that failed them is published all the
    same)."""

    t_s: float
    plane: GraspPlane
    tilt_rad: float
    tip_offset_m: float
    method: str
    kept: bool


class Machine(Protocol):
    """What the loop drives: a pure, non-blocking state machine.

    A machine that finds the plug's pose in the hand also has ``in_hand_estimates`` (a tuple
    of ``InHandEstimate``, in the order made, as ``transitions``); it is optional (read by
    ``in_hand_estimates``): a machine without it makes none."""

    @property
    def phase(self) -> Phase: ...

    @property
    def transitions(self) -> tuple[Transition, ...]: ...

    def step(self, observation: Observation) -> Command: ...


def in_hand_estimates(machine: Machine) -> tuple[InHandEstimate, ...]:
    """``machine``'s in-hand estimates so far (none for a machine without the attribute)."""
    return tuple(getattr(machine, "in_hand_estimates", ()))
