"""The product's axial-force map (the press spiral by touch, ``dipole``; the task's
``touch_spiral.axial_weights``), fitted on recorded trials against the simulator's truth
(``python -m evaluation fit_axial_map``).

Each trial record (``run_trials.py --records``: ticks.jsonl and truth.npz) gives one
sample per new tactile frame while the machine searches or pushes (SEARCH, INSERT): the
estimate's ``AXIAL_TERMS`` and the true axial force on the plug at the frame's capture
time (``wrist_wrench_t`` z: the wrist's force along T z, N). The map is their least-squares
line with an intercept, which the machine's tare takes up (the weights are kept, the
intercept dropped). Records are split by trial: the fit on some, the error reported on the
others, beside the error of the reading it replaces.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from controller.cli.support import ToolError
from controller.insertion.force_reading import AXIAL_TERMS, axial_terms

PHASES = ("search", "insert")  # the phases whose frames are samples


@dataclass(frozen=True)
class AxialSamples:
    """``terms`` (n x 9, ``AXIAL_TERMS``) and ``force_n`` (n, the true axial force, N)."""

    terms: np.ndarray
    force_n: np.ndarray


def record_samples(folder: Path) -> AxialSamples:
    """The samples of the trial recorded in ``folder``; ToolError naming the folder or file if
    it holds no ticks.jsonl and truth.npz, either is damaged (naming the tick log's line), or
    it has no estimate in SEARCH or INSERT."""
    ticks_path, truth_path = folder / "ticks.jsonl", folder / "truth.npz"
    if not (ticks_path.is_file() and truth_path.is_file()):
        raise ToolError(f"{folder}: expected a trial record (ticks.jsonl and truth.npz)")
    try:
        with np.load(truth_path) as truth:
            t_s, wrist = truth["t_s"], truth["wrist_wrench_t"][:, 2]
    except (OSError, ValueError, KeyError, IndexError) as exc:
        message = f"{truth_path}: expected a trial's truth (t_s, wrist_wrench_t): {exc}"
        raise ToolError(message) from None
    rows, forces, seen = [], [], set()
    for number, line in enumerate(ticks_path.read_text().splitlines(), start=1):
        try:
            tick = json.loads(line)
            frame_t_s = tick.get("estimate_t_s")
            if tick["phase"] not in PHASES or frame_t_s is None or frame_t_s in seen:
                continue
            terms = axial_terms([tick["estimate"][name] for name in AXIAL_TERMS[:6]])
        except (ValueError, KeyError, TypeError, AttributeError) as exc:
            message = f"{ticks_path}, line {number}: expected a tick record ({exc})"
            raise ToolError(message) from None
        seen.add(frame_t_s)
        rows.append(terms)
        forces.append(float(np.interp(frame_t_s, t_s, wrist)))
    if not rows:
        raise ToolError(f"{folder}: no tactile frame while searching or pushing")
    return AxialSamples(np.array(rows), np.array(forces))


def joined(samples: list[AxialSamples]) -> AxialSamples:
    return AxialSamples(
        np.concatenate([s.terms for s in samples]), np.concatenate([s.force_n for s in samples])
    )


def fit_weights(samples: AxialSamples) -> np.ndarray:
    """The least-squares weights (9, N per unit of each term) of the force on the terms
    and an intercept (dropped)."""
    design = np.column_stack([samples.terms, np.ones(len(samples.force_n))])
    solution, *_ = np.linalg.lstsq(design, samples.force_n, rcond=None)
    return solution[: len(AXIAL_TERMS)]


def rms_error_n(weights: np.ndarray, samples: AxialSamples) -> float:
    """The RMS error (N) of ``weights`` on ``samples``, each read relative to its mean (as
    the machine's tare reads it relative to its zero)."""
    read = samples.terms @ weights
    error = (read - read.mean()) - (samples.force_n - samples.force_n.mean())
    return float(np.sqrt(np.mean(error**2)))
