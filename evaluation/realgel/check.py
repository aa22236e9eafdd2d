"""Run estimator configurations on the real-texture tilt sequences and score them.

For each sequence (sequences.py) and configuration: a fresh ``TactileEstimator`` on the
texture's sensor profile is shown the open gel (``set_open_reference``, the sequence's open
frames, as many as its ``reference_frames``) and zeroed on the sequence's reference frames
(the grasp), then every frame is pushed and timed (the whole ``push``, one thread). Scores
(scoring.py) are on the tilt axis of the sequence: the dipole's tilt torque and, for
comparison, the FingerVision baseline's on the same field. Also counted, over the frames
after zeroing: the frames flagged ``degenerate``, the frames whose tilt is exactly zero on
both axes, and the frames the slip detector flags (incipient or gross; every sequence is slip-free).
"""

from __future__ import annotations

import time
from collections.abc import Iterable, Sequence
from dataclasses import asdict, dataclass, replace

import cv2
import numpy as np

from controller.offline.recording_support import (
    FallbackChoice,
    recording_fallback,
    uses_recording,
)
from controller.tactile.estimator import GridFlowFactory, TactileEstimator
from controller.tactile.flow import make_grid_flow
from controller.tactile.settings import EstimatorConfig
from core.sensor_profile import sensor_profile
from evaluation.realgel.scoring import held_out_fit
from evaluation.realgel.sequences import RenderedSequence, SequenceSpec, render
from evaluation.realgel.textures import TEXTURES

PUSH_RANGE = (0.3, 0.5)
NOISE_RANGE_GREY = (2.0, 4.0)


@dataclass(frozen=True)
class Row:
    """One configuration on one sequence. ``r2`` / ``rmse_rel`` / ``gain``: the tilt torque
    on the sequence's axis (scoring.HeldOutFit); ``fv_r2``: the FingerVision baseline's R^2;
    ``ms_per_frame``: median time of a push; fractions of the frames after zeroing.
    ``note``: why the configuration could not run (r2 then NaN), else empty."""

    estimator: str
    texture: str
    sequence: str
    axis: str
    push: float
    tilt_px: float
    noise_grey: float
    r2: float
    rmse_rel: float
    gain: float
    fv_r2: float
    ms_per_frame: float
    degenerate: float
    zero_tilt: float
    slip: float
    note: str = ""

    def as_dict(self) -> dict:
        return asdict(self)


def sequence_specs(
    textures: Sequence[str],
    amplitudes_px: Sequence[float],
    frames: int,
    seed: int,
    lighting: float = 0.0,
    shading: str = "moves",
    contact: str = "centred",
) -> list[SequenceSpec]:
    """Tilt about x and about y, alone and with pushing, at each amplitude, on each texture,
    under a lighting drift of ``lighting``, with the LED ``shading`` moving with the gel or
    fixed, on a ``contact`` centred or varied in aspect and position (sequences.SequenceSpec).

    The mechanics (contact, signals, push amplitude in [0.3, 0.5]) and the noise sigma (in
    [2, 4] grey levels) of a (amplitude, axis, push) combination are the same on every
    texture, and do not depend on the other amplitudes asked for; the noise itself differs
    per texture."""
    specs = []
    for amplitude in amplitudes_px:
        for pushing in (False, True):
            for axis in ("x", "y"):
                # One seed per combination: seed, amplitude in 1/1000 px, pushing, axis.
                combo_seed = ((seed * 100_000 + round(amplitude * 1000)) * 2 + pushing) * 2 + (
                    axis == "y"
                )
                rng = np.random.default_rng([combo_seed, 2])
                push = float(rng.uniform(*PUSH_RANGE)) if pushing else 0.0
                noise = float(rng.uniform(*NOISE_RANGE_GREY))
                specs.extend(
                    SequenceSpec(
                        texture,
                        axis,
                        round(push, 2),
                        amplitude,
                        round(noise, 1),
                        combo_seed,
                        frames,
                        lighting,
                        shading,
                        contact,
                    )
                    for texture in textures
                )
    return specs


class TruthGridFlow:
    """A GridFlow that returns a sequence's true displacement, area-averaged over the cells:
    the "oracle" row (the configuration's pipeline after the flow, on a perfect flow).
    ``sequence``: anything with the sequence's ``mechanics``."""

    def __init__(self, sequence: RenderedSequence, rows: int, cols: int) -> None:
        self._sequence = sequence
        self._size = (cols, rows)
        self._index = 0

    def set_reference(self, image: np.ndarray) -> None:
        self._index = 0

    def measure(self, image: np.ndarray, out: np.ndarray) -> np.ndarray:
        field = self._sequence.mechanics.relative_field(self._index)
        self._index += 1
        out[:] = cv2.resize(field, self._size, interpolation=cv2.INTER_AREA)
        return out


def truth_flow(sequence: RenderedSequence) -> GridFlowFactory:
    """The estimator's ``flow`` hook that measures ``sequence``'s true field (TruthGridFlow)
    on whatever grid the configuration has."""

    def build(config, shape_hw, rows, cols) -> TruthGridFlow:
        return TruthGridFlow(sequence, rows, cols)

    return build


def _not_run(common: dict, note: str) -> Row:
    """The row of a configuration that could not run on a sequence, saying why."""
    nan = float("nan")
    return Row(
        **common,
        r2=nan,
        rmse_rel=nan,
        gain=nan,
        fv_r2=nan,
        ms_per_frame=nan,
        degenerate=nan,
        zero_tilt=nan,
        slip=nan,
        note=note,
    )


def run_one(
    sequence: RenderedSequence,
    name: str,
    config: EstimatorConfig,
    oracle: bool = False,
    open_gel: bool = True,
) -> Row:
    """Score ``config`` on one rendered sequence; with ``oracle`` its flow is replaced by the
    true field (TruthGridFlow); without ``open_gel`` the estimator is zeroed on the grasp
    without being shown the open gel (an old recording)."""
    spec = sequence.spec
    texture = TEXTURES[spec.texture]
    common = dict(
        estimator=name,
        texture=spec.texture,
        sequence=spec.label,
        axis=spec.axis,
        push=spec.push,
        tilt_px=spec.tilt_px,
        noise_grey=spec.noise_grey,
    )
    if oracle:  # the flow is replaced below; any dense method builds without markers
        config = replace(config, flow=replace(config.flow, method="dis"))
    elif config.flow.method == "markers" and not texture.markers:
        return _not_run(common, "no markers")
    profile = sensor_profile(texture.sensor)
    # On the oracle row everything after the flow is the configuration's.
    flow = truth_flow(sequence) if oracle else make_grid_flow
    estimator = TactileEstimator(config, profile, flow=flow)
    fps = profile.fps_hz
    try:
        if open_gel:
            estimator.set_open_reference(sequence.open_frames[: config.reference_frames])
        estimator.set_reference(sequence.references[: config.reference_frames])
    except ValueError as error:
        return _not_run(common, str(error).split(";")[0])
    axis = 0 if spec.axis == "x" else 1
    divergences: list[np.ndarray] | None = [] if uses_recording(estimator, open_gel) else None
    tilt, fv, seconds, degenerate, zero, slip = _push_all(
        estimator, sequence, axis, fps, divergences
    )
    # Without the open gel, the offline tool's choice (tactile estimate): estimated again
    # about the contact's support found in the whole recording (recording_support.py).
    choice = recording_fallback(estimator, divergences or [], open_gel, flow)
    if choice is not None:
        choice.estimator.set_reference(sequence.references[: config.reference_frames])
        first_seconds = seconds
        tilt, fv, seconds, degenerate, zero, slip = _push_all(choice.estimator, sequence, axis, fps)
        seconds = seconds + first_seconds  # a frame costs both passes
    n = len(sequence.frames)
    truth = sequence.mechanics.truth[:, axis]
    fit = held_out_fit(tilt, truth)
    return Row(
        **common,
        r2=fit.r2,
        rmse_rel=fit.rmse_rel,
        gain=fit.gain,
        fv_r2=held_out_fit(fv, truth).r2,
        ms_per_frame=1e3 * float(np.median(seconds)),
        degenerate=degenerate / n,
        zero_tilt=zero / n,
        slip=slip / n,
        note=_fallback_note(choice),
    )


def _fallback_note(choice: FallbackChoice | None) -> str:
    """The row's note for the offline tool's choice without the open gel."""
    if choice is None:
        return ""
    support = ""
    if "contact_support" in choice.record:
        found = choice.record["contact_support"] is not None
        support = "recording support" if found else "whole grid"
    ungated = "ungated (no press seen)" if "noise_gate" in choice.record else ""
    return ", ".join(part for part in (support, ungated) if part)


def _push_all(
    estimator: TactileEstimator,
    sequence: RenderedSequence,
    axis: int,
    fps: float,
    divergences: list[np.ndarray] | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, int, int, int]:
    """Push every frame of ``sequence``: the tilt and the baseline's on ``axis``, the seconds
    of each push, and the counts of degenerate, zero-tilt and slip-flagged frames.
    ``divergences``: if given, each frame's ``field_divergence`` is appended to it (timed
    with the push)."""
    n = len(sequence.frames)
    tilt = np.empty(n)
    fv = np.empty(n)
    seconds = np.empty(n)
    degenerate = zero = slip = 0
    for i, frame in enumerate(sequence.frames):
        began = time.perf_counter()
        estimate = estimator.push(frame, (i + 1) / fps)
        if divergences is not None:
            divergences.append(estimator.field_divergence())
        seconds[i] = time.perf_counter() - began
        tilt[i] = (estimate.tau_x, estimate.tau_y)[axis]
        fv[i] = (estimate.fv_tau_x, estimate.fv_tau_y)[axis]
        degenerate += estimate.degenerate
        zero += estimate.tau_x == 0.0 and estimate.tau_y == 0.0
        slip += estimate.slip_suspected or estimate.slip_gross
    return tilt, fv, seconds, degenerate, zero, slip


@dataclass(frozen=True)
class Entry:
    """A configuration to score, under the label ``name``; ``oracle``: on the true field;
    ``open_gel``: shown the open gel before the grasp (False: an old recording without)."""

    name: str
    config: EstimatorConfig
    oracle: bool = False
    open_gel: bool = True


def run_check(specs: Iterable[SequenceSpec], entries: Sequence[Entry], progress=None) -> list[Row]:
    """Every entry on every sequence (each sequence rendered once), on one thread."""
    cv2.setNumThreads(1)
    references = max(entry.config.reference_frames for entry in entries)
    rows = []
    for spec in specs:
        sequence = render(spec, references)
        for entry in entries:
            rows.append(run_one(sequence, entry.name, entry.config, entry.oracle, entry.open_gel))
            if progress is not None:
                progress(rows[-1])
    return rows
