"""Markdown tables of the real-texture check (check.Row)."""

from __future__ import annotations

import math
from collections.abc import Sequence

from evaluation.realgel.check import Row


def _r2(value: float) -> str:
    return "n/a" if math.isnan(value) else f"{value:.3f}"


def _percent(value: float) -> str:
    return "n/a" if math.isnan(value) else f"{100 * value:.0f}"


def _ms(values: Sequence[float]) -> str:
    finite = sorted(v for v in values if not math.isnan(v))
    return f"{finite[len(finite) // 2]:.2f}" if finite else "n/a"


def _min(values: Sequence[float]) -> float:
    finite = [v for v in values if not math.isnan(v)]
    return min(finite) if finite else float("nan")


def _mean(values: Sequence[float]) -> float:
    finite = [v for v in values if not math.isnan(v)]
    return sum(finite) / len(finite) if finite else float("nan")


def summary_table(rows: Sequence[Row]) -> list[str]:
    """One line per estimator and tilt amplitude: the worst and mean held-out R^2 of the
    tilt without and with pushing, the worst relative RMSE, median ms per frame, and the
    mean fractions of degenerate, zero-tilt and slip-flagged frames; the FingerVision
    baseline's best R^2 on the same fields."""
    lines = [
        "| estimator | tilt px | min R² tilt | min R² push | mean R² | max RMSE/range "
        "| ms/frame | degenerate % | zero tilt % | slip flag % | FingerVision max R² |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    keys = dict.fromkeys((row.estimator, row.tilt_px) for row in rows)
    for estimator, tilt_px in keys:
        group = [r for r in rows if r.estimator == estimator and r.tilt_px == tilt_px]
        still = [r.r2 for r in group if r.push == 0]
        pushed = [r.r2 for r in group if r.push > 0]
        fv = [r.fv_r2 for r in group if not math.isnan(r.fv_r2)]
        rmse = [r.rmse_rel for r in group if not math.isnan(r.rmse_rel)]
        lines.append(
            f"| {estimator} | {tilt_px:g} | {_r2(_min(still))} | {_r2(_min(pushed))} "
            f"| {_r2(_mean([r.r2 for r in group]))} "
            f"| {_r2(max(rmse)) if rmse else 'n/a'} "
            f"| {_ms([r.ms_per_frame for r in group])} "
            f"| {_percent(_mean([r.degenerate for r in group]))} "
            f"| {_percent(_mean([r.zero_tilt for r in group]))} "
            f"| {_percent(_mean([r.slip for r in group]))} "
            f"| {_r2(max(fv)) if fv else 'n/a'} |"
        )
    return lines


def axis_table(rows: Sequence[Row]) -> list[str]:
    """One line per estimator and tilt amplitude: the worst held-out R^2 over the textures of
    each sequence kind (tilt about x, about y, each without and with pushing)."""
    kinds = [(axis, pushed) for pushed in (False, True) for axis in ("x", "y")]
    header = " | ".join(f"tilt {axis}{', push' if pushed else ''}" for axis, pushed in kinds)
    lines = [f"| estimator | tilt px | {header} |", "|---|---|" + "---|" * len(kinds)]
    keys = dict.fromkeys((row.estimator, row.tilt_px) for row in rows)
    for estimator, tilt_px in keys:
        group = [r for r in rows if r.estimator == estimator and r.tilt_px == tilt_px]
        cells = [
            _r2(_min([r.r2 for r in group if r.axis == axis and (r.push > 0) == pushed]))
            for axis, pushed in kinds
        ]
        lines.append(f"| {estimator} | {tilt_px:g} | {' | '.join(cells)} |")
    return lines


def rows_table(rows: Sequence[Row]) -> list[str]:
    """Every estimator on every sequence."""
    lines = [
        "| estimator | texture | sequence | tilt px | noise | R² | RMSE/range | gain "
        "| ms/frame | degenerate % | zero tilt % | slip flag % | FingerVision R² | note |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r.estimator} | {r.texture} | {r.sequence} | {r.tilt_px:g} | {r.noise_grey:g} "
            f"| {_r2(r.r2)} | {_r2(r.rmse_rel)} | {r.gain:.3g} "
            f"| {'n/a' if math.isnan(r.ms_per_frame) else f'{r.ms_per_frame:.2f}'} "
            f"| {_percent(r.degenerate)} | {_percent(r.zero_tilt)} | {_percent(r.slip)} "
            f"| {_r2(r.fv_r2)} | {r.note} |"
        )
    return lines
