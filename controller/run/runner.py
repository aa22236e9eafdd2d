"""The run path: one run of a task's machine on a device set, whatever the backend.

``run_task(task, controller, seed, backend=...)``:

1. builds the devices through ``drivers.registry`` (``backend: real``: the device files'
   drivers; ``backend: sim``: the simulated world behind the same Protocols, seeded by
   ``seed``);
2. picks the controller by name from ``CONTROLLERS`` (a machine and the wrench source that
   feeds it; a caller may pass a table extended with its own entries); the estimator
   applies the task's calibration (``Task.calibration``), so the machine sees N*m and N;
3. connects the devices (all of them are tried; ``DevicesNotReady`` names each that
   failed), activates the gripper, and runs the control loop until the machine
   ends, a trip, a signal or the task's time budget, with every tick handed to the
   observers (the run's record when ``out_dir`` is given; the episode writer and the live
   view hook in the same way);
4. disconnects every device (``ExitStack``), whatever happened.

This module never imports the simulator: with ``backend: real`` neither ``drivers.sim`` nor
MuJoCo is loaded (tests/controller/test_run_path.py checks it with an import blocker).
Scoring a simulated run against the world's truth is the trial tools' job
(``evaluation/trials``): the outcome carries the world as an opaque handle.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from contextlib import ExitStack
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from controller.episode.recorder import sensor_mount
from controller.episode.session import EpisodeRecording
from controller.insertion import Machine, Transition
from controller.loop import ControlLoop, LoopResult, Observer, TickRecord
from controller.run.controllers import CONTROLLERS, Controller
from controller.run.record import RunRecorder
from controller.run.task import Task
from controller.tactile import estimator_for_sensor
from core.config import ConfigError
from core.devices import Devices
from core.errors import DeviceError, DevicesNotReady
from drivers import registry

LOOP_MARGIN_S = 5.0
"""The loop's own cap beyond the machine's total timeout, s."""


@dataclass(frozen=True)
class RunOutcome:
    """A finished run: the loop's ``loop`` result, the ``machine`` (its phase and
    ``transitions``), the ``devices`` it ran on (``devices.world``: the simulated world, None
    on hardware), the wall-clock time the loop took (s), and the ``recorder`` (None without
    ``out_dir``)."""

    loop: LoopResult
    machine: Machine
    devices: registry.DeviceSet
    wall_s: float
    recorder: RunRecorder | None

    @property
    def transitions(self) -> tuple[Transition, ...]:
        return self.machine.transitions


def controller_entry(name: str, backend: str, table: Mapping[str, Controller]) -> Controller:
    """The controller ``name`` of ``table``; ConfigError (one line) if unknown, or
    simulation-only on the real backend."""
    if name not in table:
        raise ConfigError(f"controller {name!r}: expected one of {', '.join(table)}")
    entry = table[name]
    if entry.sim_only and backend != "sim":
        raise ConfigError(f"controller {name!r} reads the simulator's truth: sim only")
    return entry


def run_task(
    task: Task,
    controller: str,
    seed: int,
    *,
    backend: str = "sim",
    realtime: bool = False,
    paced: bool = False,
    out_dir: Path | None = None,
    observers: Sequence[Observer] = (),
    controllers: Mapping[str, Controller] = CONTROLLERS,
    prepare: Callable[[registry.DeviceSet], Any] | None = None,
    episode: EpisodeRecording | None = None,
    max_duration_s: float | None = None,
) -> RunOutcome:
    """Run ``task`` with ``controller`` on ``backend`` (see the module doc). ``seed``: the
    simulated world's seed (recorded only on hardware); ``realtime``: pace the simulated
    world to the wall clock (hardware always is); ``paced``: with ``realtime``, the world
    waits for a late tick (``core.clock.PacedClock``: a busy machine slows the run, the
    ticks are never late on its clock) instead of following the wall clock regardless;
    ``out_dir``: where the run's record goes
    (``RunRecorder``); ``observers``: more tick observers; ``prepare``: called with the built
    devices before they connect (e.g. a scripted gamepad); a ``DeviceSet`` it returns
    replaces them (e.g. a real gamepad in the simulated world); ``episode``: the run's episode
    (controller/episode), started once the devices are connected, that taps the wrench
    source and observes every tick; the caller closes it with the outcome;
    ``max_duration_s``: the loop's cap on its clock, s (default: the machine's
    ``timeouts.total_s`` plus ``LOOP_MARGIN_S``)."""
    entry = controller_entry(controller, backend, controllers)
    if backend == "sim" and task.scene is None:
        raise ConfigError(f"{task.path}: the task was loaded without its scene (backend real)")
    config = task.config
    world = None
    if backend == "sim":
        world = registry.WorldSpec(task.scene, config.plug, config.hole, seed, realtime, paced)
    device_set = registry.build_device_set(
        task.device_files, backend, world, arm_force=entry.arm_force
    )
    if prepare is not None:
        replaced = prepare(device_set)
        if isinstance(replaced, registry.DeviceSet):
            device_set = replaced
    estimator = estimator_for_sensor(task.tactile_model, config.estimator, task.calibration)
    source = entry.wrench_source(estimator, device_set.world, seed)
    machine = entry.machine(config)
    with ExitStack() as stack:
        connect_all(device_set.devices, stack)
        recorder = RunRecorder(out_dir) if out_dir is not None else None  # once connected
        if recorder is not None:
            stack.callback(recorder.close)
        if episode is not None:  # once connected too; the caller closes it
            episode.start(device_set.clock)
            source = episode.tap(source, device_set.clock, device_set.devices.tactile)
            mount = sensor_mount(config.machine.signals.torque_axes, config.plug.thickness_m)
            observers = [episode.observer(mount), *observers]
        ticks = _fan_out([*([recorder] if recorder is not None else []), *observers])
        device_set.devices.gripper.activate()
        began = time.perf_counter()
        loop = ControlLoop(
            machine,
            device_set.devices,
            source,
            device_set.clock,
            config.loop,
            config.limits,
            config.teleop,
            observer=ticks,
        )
        cap_s = config.machine.timeouts.total_s + LOOP_MARGIN_S
        loop_result = loop.run(max_duration_s=cap_s if max_duration_s is None else max_duration_s)
        wall_s = time.perf_counter() - began
    return RunOutcome(loop_result, machine, device_set, wall_s, recorder)


def connect_all(devices: Devices, stack: ExitStack) -> None:
    """Connect every device, each disconnected by ``stack`` when the run ends; try them
    all, then raise ``DevicesNotReady`` naming each that failed (the ones connected are
    disconnected as the stack unwinds)."""
    failures: dict[str, DeviceError] = {}
    for role, device in devices.named():
        try:
            stack.enter_context(device)
        except DeviceError as error:
            failures[role] = error
    if failures:
        raise DevicesNotReady(failures)


def _fan_out(observers: Sequence[Observer]) -> Observer | None:
    """One observer calling each of ``observers`` in order (None for none)."""
    if not observers:
        return None
    if len(observers) == 1:
        return observers[0]

    def each(tick: TickRecord) -> None:
        for observer in observers:
            observer(tick)

    return each
