"""The control loop: deadline-paced on an injected clock, it reads the devices, estimates,
lets the machine decide, limits the command and sends it.

Pacing. Tick ``k`` is due at ``start + k * period`` on the clock (``period = 1 / rate_hz``);
the loop sleeps until the deadline, never a fixed time, so a slow tick does not shift the
ticks after it. A tick that ends after the next deadline is an **overrun**; the deadlines it
missed are skipped (the next tick is the first deadline still ahead), keeping the grid. The
same loop runs in real time (``core.clock.MonotonicClock``) or as fast as possible
(``ManualClock``, whose ``sleep`` advances it at once); only the clock differs.

Tick order:

1. wait for the deadline; stop if a signal arrived or ``max_duration_s`` has passed;
2. read the gamepad and arbitrate it (``controller.teleop``); a pad lost while the operator
   is in control, or one whose read fails, trips at once (go to 7), before the tick's other
   reads and the estimator's work; read the newest tactile frame
   (``read_latest(tactile_max_age_s)``) and push it into the estimator (a ``WrenchSource``)
   if it is new; read the arm and the gripper;
3. the watchdog (``controller.safety.Watchdog``) checks the readings; on a trip go to 7;
4. build the ``Observation`` and call ``machine.step``; a ``capture_open_tactile`` command
   has the estimator take the next ``rezero_frames`` frames as the open gel, a
   ``rezero_tactile`` command re-zeroes it from the next ``rezero_frames`` frames;
5. limit the command (``controller.safety.CommandLimiter``) and send it: a twist by
   ``arm.move_velocity(twist, hold_s)``, a pose by ``arm.servo_pose``, neither: a zero twist
   once if a twist was moving the arm; a gripper target only when it differs from the last
   one sent; an error while sending goes to 7;
6. call the observer with the tick's record; stop when the machine is DONE or FAILED;
   count an overrun (the watchdog may trip on the overrun policy: go to 7);
7. on a trip: ``safe_stop`` at once, then one more ``machine.step`` with
   ``Observation.fault`` set (its command is not sent) so the machine records its failure,
   the observer sees it, and the loop ends: the stop comes within the tick that saw the
   fault, i.e. within one period of the fault being observable. Any exception raised in a
   tick (an estimator's ValueError on a wrong-size frame, a ConnectionResetError, an
   observer that cannot write) is such a trip: its type and message are the fault's.

Whatever ends the loop (the machine, a trip, a signal), a ``finally`` runs
``safe_stop`` unless the loop already did. SIGINT and SIGTERM (handlers installed only in
the main thread, the previous ones restored afterwards) end the loop at the next tick
start, i.e. within one period. ``safe_stop``'s error, if any, is in the result
(``LoopResult.safe_stop_error``) and logged.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import os
import signal
import threading
from collections.abc import Callable
from dataclasses import dataclass
from types import FrameType
from typing import Any, Literal

import numpy as np

from controller.insertion.interface import (
    Command,
    GripperTarget,
    InHandEstimate,
    Machine,
    Observation,
    Phase,
    TeleopInput,
    Transition,
    in_hand_estimates,
)
from controller.safety import CommandLimiter, LimitsConfig, Watchdog, safe_stop
from controller.tactile.estimator import TactileEstimator
from controller.tactile.wrench import WrenchEstimate
from controller.tactile.wrench_source import WrenchSource, estimator_of
from controller.teleop import TeleopArbiter, TeleopConfig
from core.clock import Clock
from core.config import Config, config_dataclass, number
from core.devices import (
    ArmStatus,
    Devices,
    GamepadState,
    GripperStatus,
    TactileFrame,
    Twist,
)
from core.errors import DeviceError

log = logging.getLogger(__name__)

_SignalHandler = Callable[[int, FrameType | None], Any] | int | signal.Handlers | None
"""A signal's handler as ``signal.signal`` takes and returns it."""

TERMINAL = (Phase.DONE, Phase.FAILED)
_EPS_S = 1e-9  # deadlines closer than this count as met (float round-off of the clock)
StopReason = Literal["done", "failed", "max_duration", "signal", "fault"]


@config_dataclass
class LoopConfig(Config):
    """The task YAML's ``loop:`` section.

    ``rate_hz``: tick rate. ``hold_s``: how long the arm holds each twist (the driver's
    velocity watchdog; at least one period). ``tactile_max_age_s``: the oldest tactile frame
    accepted. ``rezero_frames``: frames averaged into a new tactile reference on a
    ``rezero_tactile`` command. Overrun policy: the watchdog trips on
    ``max_consecutive_overruns`` overruns in a row or ``max_overruns_in_window`` within the
    last ``overrun_window_ticks`` ticks. ``rt_priority``: run the loop's thread under the
    SCHED_FIFO real-time policy at this priority (1..99; Linux, needs CAP_SYS_NICE or an
    ``rtprio`` limit), restoring its policy afterwards; None: the default scheduler.
    ``max_held_by_limits_s``: the longest the workspace or tilt limit may hold the machine's
    commands back without a break before the watchdog trips (a target outside the envelope
    is a fault, not a run that goes on against the box's face); an operator in control is
    held without tripping. On a
    shared or loaded machine this is what keeps the period error under a millisecond
    (docs/BENCHMARKS.md, "Control loop period").
    """

    rate_hz: float = number(1.0, 1000.0, default=100.0)
    hold_s: float = number(0.001, 1.0, default=0.05)
    tactile_max_age_s: float = number(0.001, 5.0, default=0.15)
    rezero_frames: int = number(1, 1000, default=5)
    max_consecutive_overruns: int = number(1, 100_000, default=5)
    max_overruns_in_window: int = number(1, 100_000, default=20)
    overrun_window_ticks: int = number(1, 100_000, default=100)
    rt_priority: int | None = number(1, 99, default=None)
    max_held_by_limits_s: float = number(0.01, 600.0, default=1.0)

    def __post_init__(self) -> None:
        if self.hold_s < 1.0 / self.rate_hz:
            raise ValueError(
                f"key 'hold_s': expected at least one period (1 / rate_hz = "
                f"{1.0 / self.rate_hz:.4g} s), got {self.hold_s!r}"
            )
        if self.max_overruns_in_window > self.overrun_window_ticks:
            raise ValueError(
                f"key 'max_overruns_in_window': expected at most overrun_window_ticks "
                f"({self.overrun_window_ticks}), got {self.max_overruns_in_window!r}"
            )

    @property
    def period_s(self) -> float:
        return 1.0 / self.rate_hz


@dataclass(frozen=True)
class TickTiming:
    """One tick on the clock (s): its index ``k``, its ``deadline_s``, when it started and
    ended, and whether it ``overran`` (ended after the next deadline)."""

    index: int
    deadline_s: float
    start_s: float
    end_s: float
    overran: bool


@dataclass(frozen=True)
class TickRecord:
    """What the observer gets each tick. ``command``: the command as sent (after the limits;
    None when nothing was sent, on a fault tick); ``limited``: the limits that changed it;
    ``phase``: the machine's phase after its step; ``fault``: the watchdog's trip message;
    ``transitions``: the machine's phase changes made since the previous record, in order;
    ``in_hand_estimates``: the machine's estimates of the plug in the hand made since the
    previous record, in order (``controller.insertion.interface.in_hand_estimates``)."""

    observation: Observation
    command: Command | None
    limited: tuple[str, ...]
    phase: Phase
    timing: TickTiming
    fault: str | None = None
    transitions: tuple[Transition, ...] = ()
    in_hand_estimates: tuple[InHandEstimate, ...] = ()


@dataclass(frozen=True)
class LoopStats:
    """Timing of a run, s. ``period_*``: between consecutive tick starts; ``lateness_*``:
    tick start minus its deadline (the period error of a deadline-paced loop); ``work_*``:
    tick start to end. ``overruns``: ticks that ended after the next deadline;
    ``skipped``: deadlines skipped because of them. ``first_tick_s``: the first tick's start
    on the loop's clock (when the machine began; NaN without ticks)."""

    ticks: int
    overruns: int
    skipped: int
    period_p50_s: float
    period_p99_s: float
    period_max_s: float
    lateness_p50_s: float
    lateness_p99_s: float
    lateness_max_s: float
    work_p50_s: float
    work_p99_s: float
    work_max_s: float
    first_tick_s: float

    @classmethod
    def of(
        cls,
        starts_s: list[float],
        deadlines_s: list[float],
        ends_s: list[float],
        overruns: int,
        skipped: int,
    ) -> LoopStats:
        """The statistics of ticks started at ``starts_s`` (NaN where there are none)."""
        starts = np.asarray(starts_s)
        periods = np.diff(starts)
        lateness = starts - np.asarray(deadlines_s)
        work = np.asarray(ends_s) - starts[: len(ends_s)]

        def pct(values: np.ndarray) -> tuple[float, float, float]:
            if values.size == 0:
                return (math.nan, math.nan, math.nan)
            p50, p99 = np.percentile(values, [50, 99])
            return (float(p50), float(p99), float(values.max()))

        first = float(starts[0]) if starts.size else math.nan
        return cls(
            len(starts_s), overruns, skipped, *pct(periods), *pct(lateness), *pct(work), first
        )


@dataclass(frozen=True)
class LoopResult:
    """How a run ended: ``reason`` (``done``/``failed``: the machine's terminal phase;
    ``max_duration``; ``signal``; ``fault``: a watchdog trip), ``message`` (the trip or the
    signal's name), the machine's final ``phase``, the timing ``stats``, and the error of the
    final safe stop, if any."""

    reason: StopReason
    message: str
    phase: Phase
    stats: LoopStats
    safe_stop_error: Exception | None = None


Observer = Callable[[TickRecord], None]


class ControlLoop:
    """Runs ``machine`` on ``devices`` (see the module doc). ``estimator`` turns tactile
    frames into estimates (a ``controller.tactile.WrenchSource``: the ``TactileEstimator``,
    or an evaluation's stand-in that wraps it); ``observer`` (optional) gets a ``TickRecord``
    every tick (the episode recorder hooks here). Use each loop for one ``run``."""

    def __init__(
        self,
        machine: Machine,
        devices: Devices,
        estimator: WrenchSource,
        clock: Clock,
        config: LoopConfig | None = None,
        limits: LimitsConfig | None = None,
        teleop: TeleopConfig | None = None,
        observer: Observer | None = None,
    ) -> None:
        self.config = config if config is not None else LoopConfig()
        self.machine = machine
        self.devices = devices
        self.estimator = estimator
        self.clock = clock
        self.observer = observer
        cfg = self.config
        self.limiter = CommandLimiter(
            limits if limits is not None else LimitsConfig(), cfg.period_s, cfg.hold_s
        )
        self.arbiter = TeleopArbiter(teleop if teleop is not None else TeleopConfig())
        self.watchdog = Watchdog(
            cfg.tactile_max_age_s,
            cfg.max_consecutive_overruns,
            cfg.max_overruns_in_window,
            cfg.overrun_window_ticks,
            cfg.max_held_by_limits_s,
        )
        self._signal: int | None = None
        self._stopped = False
        self._stop_error: Exception | None = None
        self._wrench: WrenchEstimate | None = None
        self._contact_centre_s_m: tuple[float, float] | None = None  # Observation's
        self._tactile_estimator = estimator_of(estimator)  # None: a scripted source
        self._frame_t_s: float | None = None
        self._arm_status: ArmStatus | None = None
        self._gripper_status: GripperStatus | None = None
        self._last_observation: Observation | None = None
        self._twisting = False
        self._gripper_sent: GripperTarget | None = None
        self._starts: list[float] = []
        self._deadlines: list[float] = []
        self._ends: list[float] = []
        self._overruns = 0
        self._skipped = 0
        self._transitions_seen = 0
        self._estimates_seen = 0

    # -- running -------------------------------------------------------------------------

    def run(self, max_duration_s: float | None = None) -> LoopResult:
        """Tick until the machine is DONE or FAILED, a watchdog trip, a signal, or
        ``max_duration_s`` on the clock; always ends with a safe stop."""
        scheduling = _enter_realtime(self.config.rt_priority)
        previous = self._install_signal_handlers()
        try:
            reason, message = self._run(max_duration_s)
        finally:
            try:
                self._stop_once()
            finally:
                for signum, handler in previous.items():
                    signal.signal(signum, handler)
                if scheduling is not None:
                    os.sched_setscheduler(0, *scheduling)
        return LoopResult(reason, message, self.machine.phase, self.stats(), self._stop_error)

    def stats(self) -> LoopStats:
        """Timing statistics of the ticks so far."""
        return LoopStats.of(
            self._starts, self._deadlines, self._ends, self._overruns, self._skipped
        )

    def _run(self, max_duration_s: float | None) -> tuple[StopReason, str]:
        period = self.config.period_s
        start = self.clock.now()
        k = 0
        while True:
            deadline = start + k * period
            wait = deadline - self.clock.now()
            if wait > 0:
                self.clock.sleep(wait)
            now = self.clock.now()
            if self._signal is not None:
                return "signal", signal.Signals(self._signal).name
            if max_duration_s is not None and now - start >= max_duration_s - _EPS_S:
                return "max_duration", f"{max_duration_s} s"
            self._starts.append(now)
            self._deadlines.append(deadline)
            try:
                ended = self._tick(k, deadline, now)
            except Exception as error:  # any failure in a tick ends as a device fault does
                message = f"the tick raised {type(error).__name__}: {error}"
                ended = "fault", self._fault(message, self._last_observation, k, deadline, now)
            end = self.clock.now()
            self._ends.append(end)
            if ended is not None:
                return ended
            overran = end > start + (k + 1) * period + _EPS_S
            next_k = k + 1
            if overran:
                self._overruns += 1
                next_k = max(k + 1, math.floor((end - start) / period + _EPS_S) + 1)
                self._skipped += next_k - k - 1
            trip = self.watchdog.record_tick(overran)
            if trip is not None:
                return "fault", self._fault(trip, self._last_observation, k, deadline, now)
            k = next_k

    def _tick(self, k: int, deadline: float, now: float) -> tuple[StopReason, str] | None:
        devices = self.devices
        errors: dict[str, Exception] = {}
        # the pad first: a pad lost (or failing) while the operator drives stops the arm
        # before the tick's other reads and the estimator's work
        pad: GamepadState | None = None
        if devices.gamepad is not None:
            pad = _read(devices.gamepad.read, errors, "gamepad")
        teleop = self.arbiter.update(pad) if devices.gamepad is not None else TeleopInput()
        trip = self.watchdog.check(
            now, frame_t_s=None, arm=None, gripper=None, teleop=teleop, errors=errors
        )
        if trip is not None:  # recorded with this tick's pad and the last other readings
            last = self._last_observation
            seen = None if last is None else dataclasses.replace(last, t_s=now, teleop=teleop)
            return "fault", self._fault(trip, seen, k, deadline, now)
        frame = _read(devices.tactile.read_latest, errors, "tactile",
                      self.config.tactile_max_age_s)  # fmt: skip
        if isinstance(frame, TactileFrame) and frame.t_s != self._frame_t_s:
            self._wrench = self.estimator.push(frame.image, frame.t_s)
            self._frame_t_s = frame.t_s
            self._contact_centre_s_m = _contact_centre_s_m(self._tactile_estimator)
        arm = _read(devices.arm.read_status, errors, "arm")
        if arm is not None:
            self._arm_status = arm
        gripper = _read(devices.gripper.read_status, errors, "gripper")
        if gripper is not None:
            self._gripper_status = gripper
        if self._arm_status is not None and self._gripper_status is not None:
            self._last_observation = Observation(
                now, self._wrench, self._arm_status, self._gripper_status, teleop,
                contact_centre_s_m=self._contact_centre_s_m,
            )  # fmt: skip
        else:
            self._last_observation = None
        trip = self.watchdog.check(
            now, frame_t_s=self._frame_t_s, arm=arm, gripper=gripper, teleop=teleop,
            errors=errors,
        )  # fmt: skip
        if trip is not None:
            return "fault", self._fault(trip, self._last_observation, k, deadline, now)

        observation = self._last_observation
        assert observation is not None  # both statuses were read: no error above
        command = self.machine.step(observation)
        if command.capture_open_tactile:
            self.estimator.capture_open(self.config.rezero_frames)
        if command.rezero_tactile:
            self.estimator.rezero(self.config.rezero_frames)
        limited = self.limiter.limit(command, observation.arm.tcp, observation.wrench)
        failed = self._send(limited.command)
        if failed:
            trip = self.watchdog.check(
                now, frame_t_s=None, arm=None, gripper=None, teleop=teleop, errors=failed
            )
            assert trip is not None  # an error always trips
            return "fault", self._fault(trip, observation, k, deadline, now)
        self._notify(observation, limited.command, limited.limited, k, deadline, now, None)
        trip = self.watchdog.record_limits(now, limited.limited, observation.teleop.in_control)
        if trip is not None:
            return "fault", self._fault(trip, observation, k, deadline, now)
        phase = self.machine.phase
        if phase in TERMINAL:
            return ("done" if phase is Phase.DONE else "failed"), phase.value
        return None

    def _send(self, command: Command) -> dict[str, Exception]:
        """Send ``command``; the DeviceError of the device that refused it, by role."""
        arm = self.devices.arm
        try:
            if command.twist is not None:
                arm.move_velocity(command.twist, self.config.hold_s)
                self._twisting = True
            elif command.pose is not None:
                arm.servo_pose(command.pose)
                self._twisting = False
            elif self._twisting:
                arm.move_velocity(Twist(), self.config.hold_s)
                self._twisting = False
        except DeviceError as error:
            return {"arm": error}
        target = command.gripper
        if target is not None and target != self._gripper_sent:
            try:
                self.devices.gripper.move(target.width_m, target.speed_m_s, target.force_n)
            except DeviceError as error:
                return {"gripper": error}
            self._gripper_sent = target
        return {}

    def _fault(
        self,
        message: str,
        observation: Observation | None,
        k: int,
        deadline: float,
        start: float,
    ) -> str:
        """Stop now, then let the machine see the fault (its command is dropped) and the
        observer record it. A failure of either is logged, not raised: the run has already
        stopped safely and ends with ``message``."""
        self._stop_once()
        if observation is not None:
            faulted = dataclasses.replace(observation, fault=message)
            try:
                self.machine.step(faulted)
                self._notify(faulted, None, (), k, deadline, start, message)
            except Exception as error:
                log.error("after the fault %r: %s: %s", message, type(error).__name__, error)
        return message

    def _notify(
        self,
        observation: Observation,
        command: Command | None,
        limited: tuple[str, ...],
        k: int,
        deadline: float,
        start: float,
        fault: str | None,
    ) -> None:
        if self.observer is None:
            return
        end = self.clock.now()
        overran = end > deadline + self.config.period_s + _EPS_S
        timing = TickTiming(k, deadline, start, end, overran)
        made = self.machine.transitions[self._transitions_seen :]
        self._transitions_seen += len(made)
        estimated = in_hand_estimates(self.machine)[self._estimates_seen :]
        self._estimates_seen += len(estimated)
        self.observer(
            TickRecord(
                observation, command, limited, self.machine.phase, timing, fault, made, estimated
            )
        )

    def _stop_once(self) -> None:
        if self._stopped:
            return
        self._stopped = True
        self._stop_error = safe_stop(self.devices.arm, self.devices.gripper)
        if self._stop_error is not None:
            log.warning("safe stop: %s", self._stop_error)

    # -- signals ---------------------------------------------------------------------------

    def _install_signal_handlers(self) -> dict[signal.Signals, _SignalHandler]:
        """Catch SIGINT and SIGTERM for the run, except a signal the process ignores (a
        batch's worker leaves SIGINT to its parent, as nohup leaves SIGHUP)."""
        if threading.current_thread() is not threading.main_thread():
            return {}
        previous: dict[signal.Signals, _SignalHandler] = {}
        for signum in (signal.SIGINT, signal.SIGTERM):
            if signal.getsignal(signum) is not signal.SIG_IGN:
                previous[signum] = signal.signal(signum, self._on_signal)
        return previous

    def _on_signal(self, signum: int, frame: FrameType | None) -> None:
        del frame
        self._signal = signum


def _enter_realtime(priority: int | None) -> tuple[int, os.sched_param] | None:
    """Switch the calling thread to SCHED_FIFO at ``priority``; its previous policy and
    parameters (None: nothing changed). PermissionError naming the key if refused."""
    if priority is None:
        return None
    if not hasattr(os, "sched_setscheduler"):
        raise OSError("loop: key 'rt_priority': SCHED_FIFO is not available on this system")
    previous = (os.sched_getscheduler(0), os.sched_getparam(0))
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))
    except PermissionError:
        raise PermissionError(
            f"loop: key 'rt_priority': SCHED_FIFO priority {priority} refused; grant "
            "CAP_SYS_NICE or an rtprio limit (/etc/security/limits.conf), or set it to null"
        ) from None
    return previous


def _read(read: Callable[..., Any], errors: dict[str, Exception], role: str, *args: Any) -> Any:
    """``read(*args)``, or None with the DeviceError recorded under ``role``."""
    try:
        return read(*args)
    except DeviceError as error:
        errors[role] = error
        return None


def _contact_centre_s_m(estimator: TactileEstimator | None) -> tuple[float, float] | None:
    """Where the grasp presses the gel (x, y in S, m) as ``estimator`` last measured it
    against the open gel; None without an estimator (a scripted source) or before a
    measurement."""
    centre_mm = None if estimator is None else estimator.contact_centre_mm
    return None if centre_mm is None else (centre_mm[0] * 1e-3, centre_mm[1] * 1e-3)
