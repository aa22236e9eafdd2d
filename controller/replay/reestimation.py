"""Re-running an estimator configuration on an episode's logged frames.

The loop's calls into the wrench source are logged in order on ``/tactile/push`` (pushes,
``capture_open``, ``rezero``); ``reestimate`` repeats them on a fresh estimator built for
the episode's tactile sensor with the configuration asked for, pushing each logged frame at
its capture time. With the run's own configuration and frames logged losslessly (PNG, the
recorder's ``tactile_image_format``) this is the run's estimator again, so its estimates are
the logged ones bit for bit (tests/controller/replay check it); JPEG frames differ from what
the estimator saw, by the compression.

Scores, per torque axis (tau_x, tau_y, tau_z):

* against the simulator's truth (``/sim/truth``, the gel's torque on the plug in S, N*m)
  where the episode has it: ``truth ~= slope * estimate + offset`` fitted over every frame
  estimated against a reference (not while zeroing;
  ``controller.tactile.calibration.fit_axis``: truth interpolated to the frames' times), its
  R^2 and RMSE (N*m) -- what a calibration would reach. The offset is there because the
  estimator is zeroed in the grasp: the grasp's own torque is in the truth, not in the
  estimate;
* against the logged estimates (always, when logged): R^2 of the logged series explained by
  the new one without any fit, RMSE in raw units, and how many frames agree exactly.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml

from controller.episode import Episode
from controller.episode.topics import (
    ATTACHMENT_CALIBRATION,
    ATTACHMENT_TASK,
    TACTILE_IMAGE,
    TACTILE_PUSH,
)
from controller.replay import episode_streams
from controller.tactile import TactileEstimator, WrenchEstimate, estimator_for_sensor
from controller.tactile.calibration import Calibration, fit_axis
from controller.tactile.settings import EstimatorConfig
from core.config import CONFIG_ROOT, ConfigError
from drivers import registry

AXES = ("tau_x", "tau_y", "tau_z")
TRUTH_COLUMNS = {"tau_x": 3, "tau_y": 4, "tau_z": 5}
"""Each torque's column in the truth's ``gel_wrench_s`` (fx, fy, fz, tau_x, tau_y, tau_z)."""


class ReestimationError(ValueError):
    """An episode that cannot be re-estimated (one line)."""


@dataclass(frozen=True)
class RunEstimator:
    """The sensor the episode was recorded with (its profile's name), the estimator
    configuration the run used (a name in configs/estimators/ or a path) and the calibration
    it applied (None: its estimates were raw)."""

    sensor: str
    estimator: str
    calibration: Calibration | None = None


def run_estimator(episode: Episode) -> RunEstimator:
    """The sensor and estimator configuration of the run, from its resolved task file (the
    ``task.yaml`` attachment: ``devices.tactile`` and ``estimator``, null meaning the
    sensor profile's own). ReestimationError if the episode does not say."""
    text = episode.attachments.get(ATTACHMENT_TASK)
    if text is None:
        raise ReestimationError(f"no '{ATTACHMENT_TASK}' attachment: which sensor is unknown")
    try:
        task = yaml.safe_load(text)
        tactile = Path(task["devices"]["tactile"])
        spec = registry.load_device_config(
            tactile if tactile.is_absolute() else CONFIG_ROOT / tactile, kind="tactile"
        )
    except (yaml.YAMLError, KeyError, TypeError, OSError, ConfigError) as exc:
        raise ReestimationError(
            f"cannot tell the sensor from '{ATTACHMENT_TASK}' (devices.tactile): {exc}"
        ) from None
    sensor = str(spec.config.model)
    estimator = task.get("estimator")
    if estimator is None:
        estimator = estimator_for_sensor(sensor).config_name
    return RunEstimator(sensor, str(estimator), run_calibration(episode))


def run_calibration(episode: Episode) -> Calibration | None:
    """The calibration the run applied (the ``calibration.yaml`` attachment), None if it
    applied none; ReestimationError if the attachment cannot be read."""
    text = episode.attachments.get(ATTACHMENT_CALIBRATION)
    if text is None:
        return None
    try:
        return Calibration.from_document(yaml.safe_load(text), ATTACHMENT_CALIBRATION)
    except (yaml.YAMLError, ConfigError, ValueError) as exc:
        raise ReestimationError(f"cannot read '{ATTACHMENT_CALIBRATION}': {exc}") from None


def calibration_for(run: RunEstimator, config: EstimatorConfig) -> Calibration | None:
    """The run's calibration if it fits the estimator configuration ``config`` on the
    run's sensor (the same configuration's values), else None (the estimates stay raw)."""
    if run.calibration is None or run.calibration.mismatch(run.sensor, config) is not None:
        return None
    return run.calibration


@dataclass(frozen=True)
class Reestimate:
    """The new estimates: per push, the frame's ``push_index``, capture time ``t_s``, the
    estimate and the estimator's time for it (ms)."""

    push_index: np.ndarray
    t_s: np.ndarray
    estimates: list[WrenchEstimate]
    latency_ms: np.ndarray

    def column(self, name: str) -> np.ndarray:
        return np.array([getattr(e, name) for e in self.estimates], dtype=float)


def reestimate(
    episode: Episode, estimator: TactileEstimator, clock: Callable[[], float]
) -> Reestimate:
    """Repeat the episode's calls into the wrench source on ``estimator`` (see the module
    doc); ``clock`` (s) times each push. In a file cut short the calls end with the last
    logged frame. ReestimationError if the episode logged no calls, or the writer dropped
    frames or calls (the frames could no longer be matched to their pushes)."""
    calls = episode_streams.source_calls(episode)
    if not calls:
        raise ReestimationError("no calls into the wrench source (/tactile/push) were logged")
    _, dropped = episode_streams.drops(episode)
    lost = {t: dropped[t] for t in (TACTILE_IMAGE.name, TACTILE_PUSH.name) if dropped.get(t)}
    if lost:
        counts = ", ".join(f"{count} on {topic}" for topic, count in lost.items())
        raise ReestimationError(
            f"the writer dropped records ({counts}): the frames cannot be matched to the "
            "estimator's calls"
        )
    logged = list(episode_streams.frames(episode))
    pushes, times, found, latency = [], [], [], []
    for call in calls:
        if call.call == "capture_open":
            estimator.capture_open(call.n_frames)
        elif call.call == "rezero":
            estimator.rezero(call.n_frames)
        else:
            if call.push_index >= len(logged):  # cut short after this call
                break
            frame = logged[call.push_index]
            t_s = frame.capture_t_s if call.frame_t_s is None else call.frame_t_s
            image = frame.image()
            began = clock()
            found.append(estimator.push(image, t_s))
            latency.append((clock() - began) * 1e3)
            pushes.append(call.push_index)
            times.append(t_s)
    return Reestimate(np.array(pushes, dtype=int), np.array(times), found, np.array(latency))


@dataclass(frozen=True)
class AxisScore:
    """One axis: ``r2`` and ``rmse`` (N*m against the truth, raw units against the logged
    estimates), the ``samples`` used, and against the logged estimates the frames that
    agree exactly (``exact``)."""

    axis: str
    r2: float
    rmse: float
    samples: int
    exact: int | None = None


def against_truth(new: Reestimate, truth: episode_streams.Truth) -> list[AxisScore]:
    """Per axis: the fit of the truth on the new estimates over the frames estimated against
    a reference (see the module doc); NaN scores where too few are."""
    referenced = np.array([not e.zeroing for e in new.estimates], dtype=bool)
    scores = []
    for axis in AXES:
        values = new.column(axis)
        use = referenced & np.isfinite(values)
        column = truth.gel_wrench_s[:, TRUTH_COLUMNS[axis]]
        try:
            fit = fit_axis(new.t_s[use], values[use], truth.t_s, column, with_offset=True)
        except ValueError:
            scores.append(AxisScore(axis, math.nan, math.nan, int(use.sum())))
            continue
        scores.append(AxisScore(axis, fit.r2, fit.rmse, fit.samples))
    return scores


def against_logged(new: Reestimate, logged: episode_streams.Estimates) -> list[AxisScore]:
    """Per axis: the new estimates against the logged ones of the same pushes (no fit)."""
    by_push = {int(p): i for i, p in enumerate(logged.push_index)}
    pairs = [(j, by_push[int(p)]) for j, p in enumerate(new.push_index) if int(p) in by_push]
    mine = np.array([j for j, _ in pairs], dtype=int)
    theirs = np.array([i for _, i in pairs], dtype=int)
    scores = []
    for axis in AXES:
        a = new.column(axis)[mine]
        b = logged.column(axis)[theirs]
        same = (a == b) | (np.isnan(a) & np.isnan(b))
        both = np.isfinite(a) & np.isfinite(b)
        residual = b[both] - a[both]
        total = float(((b[both] - b[both].mean()) ** 2).sum()) if both.any() else 0.0
        rmse = float(np.sqrt(np.mean(residual**2))) if both.any() else math.nan
        r2 = 1.0 - float((residual**2).sum()) / total if total > 0 else math.nan
        scores.append(AxisScore(axis, r2, rmse, int(both.sum()), int(same.sum())))
    return scores
