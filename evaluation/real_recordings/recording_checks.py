"""The checks of an estimate on a recording against its true program.

A recording (evaluation/real_recordings/recording_video.py) is estimated by
``tactile estimate``'s own code (controller/cli/estimate.py ``estimate_file``,
zeroed on frame 0, no calibration: raw values), and the estimate's CSV is held against the
truth CSV:

1. **finite**: every frame's tau_x, tau_y, tau_z is finite;
2. **quiet before contact**: ``quiet_ratio``, the largest |tau| = hypot(tau_x, tau_y) over
   the frames before the object first touches the gel, over its largest value in the whole
   recording, is at most ``QUIET_MAX`` (5%);
3. **sign**: in each tilt segment (``tilt_x+``, ``tilt_x-``, ``tilt_y+``, ``tilt_y-``), over
   the frames whose true torque on the segment's axis is at least ``SIGN_FLOOR`` (20%) of
   its peak over the recording, the estimate on that axis has the true sign in at least
   ``SIGN_MIN`` (95%) of frames (``sign_agreement``: the worst segment); and the correlation
   of estimate and truth on each axis over that axis's tilt phase is positive
   (``correlation``: the lower axis).

``ms_per_frame`` is the mean of the CSV's ``latency_ms`` (the estimator's whole ``push``).
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from controller.cli.estimate import estimate_file
from evaluation.real_recordings.recording_video import (
    VIDEO_SUFFIX,
    Truth,
    capture_sensor,
    read_truth,
)

QUIET_MAX = 0.05
SIGN_FLOOR = 0.2
SIGN_MIN = 0.95
SEGMENTS = {"tilt_x+": 0, "tilt_x-": 0, "tilt_y+": 1, "tilt_y-": 1}
"""Tilt segment -> the axis (0: x, 1: y) whose torque it drives."""


@dataclass(frozen=True)
class Estimate:
    """An estimate CSV's tilt torques (N, 2) raw, all three torques' finiteness per frame
    and the latency per frame, ms."""

    tau: np.ndarray
    finite: np.ndarray
    latency_ms: np.ndarray


@dataclass(frozen=True)
class RecordingCheck:
    """The checks of the module docstring for one estimator on one recording."""

    estimator: str
    capture: str
    frames: int
    finite: float
    quiet_ratio: float
    sign_agreement: float
    correlation: float
    ms_per_frame: float

    @property
    def passed(self) -> bool:
        return (
            self.finite == 1.0
            and self.quiet_ratio <= QUIET_MAX
            and self.sign_agreement >= SIGN_MIN
            and self.correlation > 0.0
        )


def read_estimate(path: Path) -> Estimate:
    """The estimate CSV written by ``tactile estimate``."""
    with open(path, newline="") as handle:
        rows = list(csv.DictReader(handle))
    torques = np.array([[float(r["tau_x"]), float(r["tau_y"]), float(r["tau_z"])] for r in rows])
    return Estimate(
        tau=torques[:, :2],
        finite=np.isfinite(torques).all(axis=1),
        latency_ms=np.array([float(r["latency_ms"]) for r in rows]),
    )


def quiet_ratio(tau: np.ndarray, contact: np.ndarray) -> float:
    """Largest |tau| before the first contact frame over the largest |tau| overall
    (``tau`` (N, 2); inf when there is no contact-free start or the estimate is all zero)."""
    if not contact.any() or contact[0]:
        return float("inf")
    magnitude = np.hypot(tau[:, 0], tau[:, 1])
    peak = float(np.nanmax(magnitude))
    if not peak > 0:
        return float("inf")
    return float(np.nanmax(magnitude[: int(np.argmax(contact))]) / peak)


def segment_agreement(tau: np.ndarray, truth: Truth) -> dict[str, float]:
    """Per tilt segment, the share of its frames above ``SIGN_FLOOR`` of the axis's peak
    true torque where the estimate has the true sign (nan: no such frame)."""
    segments = np.array(truth.segments)
    peak = np.abs(truth.tau_nm).max(axis=0)
    shares = {}
    for name, axis in SEGMENTS.items():
        loaded = (segments == name) & (np.abs(truth.tau_nm[:, axis]) >= SIGN_FLOOR * peak[axis])
        agree = np.sign(tau[loaded, axis]) == np.sign(truth.tau_nm[loaded, axis])
        shares[name] = float(agree.mean()) if loaded.any() else float("nan")
    return shares


def axis_correlation(tau: np.ndarray, truth: Truth) -> tuple[float, float]:
    """Pearson correlation of estimate and truth on x over the ``tilt_x`` phase and on y
    over ``tilt_y`` (nan for a constant series)."""
    segments = np.array(truth.segments)
    out = []
    for axis, phase in enumerate(("tilt_x", "tilt_y")):
        rows = np.char.startswith(segments, phase)
        est, true = tau[rows, axis], truth.tau_nm[rows, axis]
        if len(est) < 2 or np.std(est) == 0 or np.std(true) == 0 or not np.isfinite(est).all():
            out.append(float("nan"))
        else:
            out.append(float(np.corrcoef(est, true)[0, 1]))
    return out[0], out[1]


def score(estimate: Estimate, truth: Truth, estimator: str, capture: str) -> RecordingCheck:
    """The checks of one estimate against its truth (nan scores fail)."""
    if len(estimate.tau) != len(truth.segments):
        raise ValueError(
            f"{capture}: the estimate has {len(estimate.tau)} frames, the truth "
            f"{len(truth.segments)}"
        )
    agreement = segment_agreement(estimate.tau, truth)
    correlation = axis_correlation(estimate.tau, truth)
    return RecordingCheck(
        estimator=estimator,
        capture=capture,
        frames=len(estimate.tau),
        finite=float(estimate.finite.mean()),
        quiet_ratio=quiet_ratio(estimate.tau, truth.contact),
        sign_agreement=float(np.min(list(agreement.values()))),
        correlation=float(np.min(correlation)),
        ms_per_frame=float(estimate.latency_ms.mean()),
    )


def check_recording(capture: str, folder: Path, estimator: str) -> RecordingCheck:
    """Estimate the recording ``folder/<capture>.mkv`` with ``estimator`` (a name of
    configs/estimators or a YAML path) through ``tactile estimate``'s code, writing
    ``folder/<capture>.<estimator>.csv``, and check it against ``folder/<capture>.csv``."""
    out_csv = folder / f"{capture}.{Path(estimator).stem}.csv"
    video = folder / f"{capture}{VIDEO_SUFFIX}"
    estimate_file(video, out_csv, sensor=capture_sensor(capture), method=estimator)
    return score(read_estimate(out_csv), read_truth(folder / f"{capture}.csv"), estimator, capture)


def table(checks: list[RecordingCheck]) -> list[str]:
    """Markdown rows: estimator x capture."""
    lines = [
        "| estimator | capture | frames | finite | quiet ratio | sign agreement "
        "| correlation | ms/frame | pass |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for c in checks:
        lines.append(
            f"| `{c.estimator}` | {c.capture} | {c.frames} | {c.finite:.0%} | "
            f"{c.quiet_ratio:.3f} | {c.sign_agreement:.0%} | {c.correlation:.3f} | "
            f"{c.ms_per_frame:.1f} | {'yes' if c.passed else '**no**'} |"
        )
    return lines
