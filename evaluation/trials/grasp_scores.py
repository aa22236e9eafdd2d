"""FEEL's estimate of the plug in the hand, scored against the scene's truth per trial
(``TrialResult``'s pose fields, evaluation/trials/grasp_truth.py): the summary's block, the
errors charts.py histograms and the ``grasp_scores`` tool's table.

Six quantities (``QUANTITIES``), each scored on the trials that have an estimate of it:

* ``thickness_tilt_deg``: the tilt about T x (the thickness plane), where
  ``grasp_tilt_thickness_est_rad`` is finite (the press spiral's FEEL: ``dipole`` and the
  other controllers of its machine);
* ``thickness_tilt_receptacle_deg``: the same estimate against the plug's tilt from the
  receptacle's axis (``thickness_tilt_to_receptacle_true_rad``), which FEEL's flat face on the
  board measures: the board's tilt (up to 1 degree) is not an error of the rock;
* ``tip_y_mm``: the tip's offset along T y that tilt implies (``tip_y_est_m``);
* ``width_tilt_deg``: the tilt about T y (the width plane), where ``grasp_tilt_est_rad`` is
  finite (the press spiral's FEEL with ``rock.width``, or the ``align`` machine's);
* ``width_tilt_receptacle_deg``: the same estimate against the plug's tilt from the
  receptacle's axis in that plane (``width_tilt_to_receptacle_true_rad``);
* ``tip_x_mm``: the tip's offset along T x that tilt implies (``tip_x_est_m``; the press
  spiral's adds the next);
* ``imprint_mm``: the plug's offset across the fingers that the press spiral takes from the
  grasp's imprint on the gel (``imprint_offset_est_m``; controller/insertion/imprint.py).

A quantity no trial estimates is "not estimated": its true size is given for scale. The
summary's statistics are of the absolute error (estimate - truth); the histograms show the
signed error.

``board_share``: how much of a plane's errors the board's tilt explains (``PLANES``). FEEL
reads the plug against the receptacle's axis, which differs from the plug's tilt in the hand
by the board's tilt in that plane (b = the tilt from the receptacle's axis less the tilt in
the hand); an estimate exact against the receptacle's axis is off the hand's truth by b, and
its tip by L (sin(a + b) - sin a).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from controller.run.result import TrialResult


@dataclass(frozen=True)
class Quantity:
    """One scored quantity: ``key`` (the summary's), ``label`` (charts and tables), ``unit``,
    the ``TrialResult`` fields of its ``estimate`` and ``truth`` and the ``scale`` from theirs
    (rad, m) to ``unit``; a trial counts where ``estimate``, ``gate`` (the plane's tilt
    estimate) and ``truth`` are finite (a table from before a truth column has none)."""

    key: str
    label: str
    unit: str
    estimate: str
    truth: str
    scale: float
    gate: str


QUANTITIES = (
    Quantity("thickness_tilt_deg", "tilt about T x (thickness plane)", "deg",
             "grasp_tilt_thickness_est_rad", "grasp_tilt_thickness_true_rad", math.degrees(1.0),
             "grasp_tilt_thickness_est_rad"),
    Quantity("thickness_tilt_receptacle_deg", "tilt about T x from the receptacle's axis", "deg",
             "grasp_tilt_thickness_est_rad", "thickness_tilt_to_receptacle_true_rad",
             math.degrees(1.0), "grasp_tilt_thickness_est_rad"),
    Quantity("tip_y_mm", "tip offset along T y", "mm", "tip_y_est_m", "tip_y_true_m", 1e3,
             "grasp_tilt_thickness_est_rad"),
    Quantity("width_tilt_deg", "tilt about T y (width plane)", "deg", "grasp_tilt_est_rad",
             "grasp_tilt_true_rad", math.degrees(1.0), "grasp_tilt_est_rad"),
    Quantity("width_tilt_receptacle_deg", "tilt about T y from the receptacle's axis", "deg",
             "grasp_tilt_est_rad", "width_tilt_to_receptacle_true_rad", math.degrees(1.0),
             "grasp_tilt_est_rad"),
    Quantity("tip_x_mm", "tip offset along T x", "mm", "tip_x_est_m", "tip_x_true_m", 1e3,
             "grasp_tilt_est_rad"),
    Quantity("imprint_mm", "plug offset across the fingers (imprint)", "mm",
             "imprint_offset_est_m", "imprint_true_m", 1e3, "imprint_offset_est_m"),
)  # fmt: skip
"""The scored quantities, the thickness plane's first."""

_BY_KEY = {q.key: q for q in QUANTITIES}


def quantity(key: str) -> Quantity:
    """The quantity named ``key`` (KeyError if none)."""
    return _BY_KEY[key]


def _finite(result: TrialResult, name: str) -> bool:
    return math.isfinite(getattr(result, name))


def _estimated(results: Iterable[TrialResult], q: Quantity) -> list[TrialResult]:
    return [r for r in results if all(_finite(r, f) for f in (q.gate, q.estimate, q.truth))]


def signed_errors(results: Iterable[TrialResult], q: Quantity) -> list[float]:
    """(estimate - truth) of ``q`` in its unit, one per trial with an estimate of it."""
    return [
        q.scale * (getattr(r, q.estimate) - getattr(r, q.truth)) for r in _estimated(results, q)
    ]


def estimated(results: Sequence[TrialResult]) -> list[Quantity]:
    """The quantities some trial of ``results`` has an estimate of, in ``QUANTITIES``'s
    order."""
    return [q for q in QUANTITIES if _estimated(results, q)]


def _stats(values: Sequence[float]) -> dict[str, float] | None:
    """n, median, 95th percentile and largest of ``|values|``; None without any."""
    if not values:
        return None
    v = np.abs(np.asarray(values, float))
    return {
        "n": len(v),
        "median": float(np.median(v)),
        "p95": float(np.percentile(v, 95)),
        "max": float(v.max()),
    }


def grasp_estimate_summary(results: Sequence[TrialResult]) -> dict[str, Any] | None:
    """The summary's ``grasp_estimate`` block: ``estimated`` (the trials with an estimate
    in either plane) ``of`` all; ``errors``: for each estimated quantity (``QUANTITIES``'
    keys), the absolute error's ``n``, ``median``, ``p95`` and ``max`` (deg, mm); and
    ``not_estimated``: for each quantity no trial estimates, the same of its true size
    (over the trials with a truth; none without), for scale. None when no trial has an estimate (a
    controller without FEEL, or FEEL never ran)."""
    scored = estimated(results)
    if not scored:
        return None
    gates = {q.gate for q in scored}
    with_estimate = [r for r in results if any(_finite(r, g) for g in gates)]
    not_estimated = {}
    for q in QUANTITIES:
        truth = [q.scale * getattr(r, q.truth) for r in results if _finite(r, q.truth)]
        if q not in scored and truth:
            not_estimated[q.key] = _stats(truth)
    return {
        "estimated": len(with_estimate),
        "of": len(results),
        "errors": {q.key: _stats(signed_errors(results, q)) for q in scored},
        "not_estimated": not_estimated,
    }


@dataclass(frozen=True)
class Plane:
    """One plane of FEEL's estimate for ``board_share``: its ``name``, the axis its tilt
    turns about (``about``) and the axis its tip moves along (``along``), the quantity of its
    tilt (``tilt``: its estimate and truth), the ``TrialResult`` field of the tilt from the
    receptacle's axis (``to_receptacle``) and the quantity of its tip (``tip``)."""

    name: str
    about: str
    along: str
    tilt: str
    to_receptacle: str
    tip: str


PLANES = (
    Plane("thickness", "T x", "T y", "thickness_tilt_deg",
          "thickness_tilt_to_receptacle_true_rad", "tip_y_mm"),
    Plane("width", "T y", "T x", "width_tilt_deg", "width_tilt_to_receptacle_true_rad",
          "tip_x_mm"),
)  # fmt: skip
"""The planes whose errors ``board_share`` splits."""


def board_share(
    results: Sequence[TrialResult], length_m: float, plane: Plane
) -> dict[str, float] | None:
    """The board's part of ``plane``'s errors over the trials with an estimate and both
    truths (module doc; ``length_m``: the plug's length L from the TCP to the tip, m): ``n``;
    ``board_tilt_median_deg``, the median |b|; ``correlation`` of the tilt's signed error with
    b; ``tip_error_less_board_median_mm``, the median |tip error - the board's share of it|
    (where the tip is estimated and true). None below 3 trials or without spread in either
    (no correlation)."""
    q, tip = quantity(plane.tilt), quantity(plane.tip)
    rows = [r for r in _estimated(results, q) if _finite(r, plane.to_receptacle)]
    if len(rows) < 3:
        return None
    tilt = np.array([getattr(r, q.truth) for r in rows])
    board = np.array([getattr(r, plane.to_receptacle) for r in rows]) - tilt
    error = np.array([getattr(r, q.estimate) for r in rows]) - tilt
    if np.ptp(board) == 0.0 or np.ptp(error) == 0.0:
        return None
    share_m = length_m * (np.sin(tilt + board) - np.sin(tilt))
    off = np.array([getattr(r, tip.estimate) - getattr(r, tip.truth) for r in rows]) - share_m
    off = np.abs(off[np.isfinite(off)])
    return {
        "n": len(rows),
        "board_tilt_median_deg": math.degrees(float(np.median(np.abs(board)))),
        "correlation": float(np.corrcoef(error, board)[0, 1]),
        "tip_error_less_board_median_mm": 1e3 * float(np.median(off)) if off.size else math.nan,
    }


def board_shares(results: Sequence[TrialResult], length_m: float) -> dict[str, Any]:
    """``board_share`` of each of ``PLANES``, by its name (None where it has none)."""
    return {plane.name: board_share(results, length_m, plane) for plane in PLANES}


def chart_errors(results: Sequence[TrialResult]) -> dict[str, list[float]]:
    """The signed errors of each estimated quantity, by its axis label (unit included): what
    ``charts.grasp_error_chart`` draws."""
    return {f"{q.label}, {q.unit}": signed_errors(results, q) for q in estimated(results)}


TABLE_HEADER = (
    "quantity", "estimated", "median \\|error\\|", "p95 \\|error\\|", "max \\|error\\|"
)  # fmt: skip
"""The columns of ``table_cells``'s rows (markdown: the bars escaped)."""


def table_cells(block: dict[str, Any]) -> list[list[str]]:
    """A summary block's rows for a markdown table (``TABLE_HEADER``): each estimated
    quantity's absolute errors (n of all trials), then each one not estimated, its true
    size in parentheses (for scale)."""
    rows = []
    for key, stats in block["errors"].items():
        q = quantity(key)
        rows.append([
            f"{q.label}, {q.unit}", f"{stats['n']}/{block['of']}",
            f"{stats['median']:.2f}", f"{stats['p95']:.2f}", f"{stats['max']:.2f}",
        ])  # fmt: skip
    for key, stats in block["not_estimated"].items():
        q = quantity(key)
        size = ["–"] * 3 if stats is None else [
            f"({stats['median']:.2f})", f"({stats['p95']:.2f})", f"({stats['max']:.2f})"
        ]  # fmt: skip
        rows.append([f"{q.label}, {q.unit}", "not estimated", *size])
    return rows
