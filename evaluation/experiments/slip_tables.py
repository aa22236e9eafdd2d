"""Markdown tables of a slip evaluation (``evaluation.experiments.slip_eval.report``)."""

from __future__ import annotations

import numpy as np

from core.sensor_profile import sensor_profile
from evaluation.experiments.slip_eval import INCIPIENT_SLIP_FRACTION, SENSOR, precision_recall


def slip_tables(report: dict) -> list[str]:
    """The definitions, the precision/recall table per grip and object with the tuning,
    held-out and overall totals, and the per-sequence delays."""
    lines = [
        f"Per frame: incipient = slip fraction >= {INCIPIENT_SLIP_FRACTION:g} or gross slip "
        "(flag `slip_suspected`); gross = the model's gross slip (flag `slip_gross`). Delay: "
        "median over the sequences of the first flagged minus the first true frame (frames "
        f"at {sensor_profile(SENSOR).fps_hz:g} Hz). False alarms: share of the negative "
        "sequences' frames flagged `slip_suspected`.",
        "",
        "| grip N | object | incipient P | incipient R | gross P | gross R | delay incipient "
        "/ gross | negatives flagged | re-zero after gross | re-zero under load |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    totals = [{"grip_n": "all", "object": "all", **report["overall"]}]
    if report["held_out"] is not None:
        tuned = f"{report['tuned_on_grip_n']:g} (tuning)"
        totals = [
            {"grip_n": tuned, "object": "all", **report["tuning"]},
            {"grip_n": "others (held out)", "object": "all", **report["held_out"]},
            *totals,
        ]
    for g in [*report["groups"], *totals]:
        grip = g["grip_n"] if isinstance(g["grip_n"], str) else f"{g['grip_n']:g}"
        lines.append(
            f"| {grip} | {g['object']} | {_fmt(g['incipient']['precision'])} | "
            f"{_fmt(g['incipient']['recall'])} | {_fmt(g['gross']['precision'])} | "
            f"{_fmt(g['gross']['recall'])} | {_delays(g['incipient_delays'])} / "
            f"{_delays(g['gross_delays'])} | {g['negative_false_alarm_rate']:.1%} | "
            f"{g['rezero_after_gross']}/{g['gross_sequences']} | "
            f"{g['rezero_under_load_frames']} frames |"
        )
    lines += [
        "",
        "Detection delay in frames (first flagged minus first true frame):",
        "",
        "| grip N | object | sequence | incipient delay | gross delay | flagged frames |",
        "|---|---|---|---|---|---|",
    ]
    for row in report["sequences"]:
        incipient = _delay_text(row["incipient_delay"]) if "incipient_delay" in row else "-"
        gross = _delay_text(row["gross_delay"]) if "gross_delay" in row else "-"
        lines.append(
            f"| {row['grip_n']:g} | {row['object']} | {row['name']} | {incipient} | {gross} | "
            f"{row['flagged_frames']}/{row['frames']} |"
        )
    return lines


def _fmt(value: float) -> str:
    return "-" if value != value else f"{value:.2f}"


def _delays(values: list[int | None]) -> str:
    """Median delay in frames, and how many sequences were never flagged."""
    found = [v for v in values if v is not None]
    median = f"{float(np.median(found)):+.1f}" if found else "-"
    missed = len(values) - len(found)
    return median + (f" ({missed} missed)" if missed else "")


def _delay_text(value: int | None) -> str:
    return "missed" if value is None else f"{value:+d}"


def sweep_slip_table(sweeps: dict) -> list[str]:
    """Precision and recall of the slip flags over every frame of each stability sweep
    (``sweeps``: condition name -> its ``LevelResult`` list), and over all of them."""
    lines = [
        "| condition | frames slipping (incipient / gross) | incipient P | incipient R | "
        "gross P | gross R | frames flagged |",
        "|---|---|---|---|---|---|---|",
    ]
    totals = {"incipient": np.zeros(3, int), "gross": np.zeros(3, int)}
    rows = []
    for name, levels in sweeps.items():
        counts = {k: np.sum([r.slip_counts[k] for r in levels], axis=0) for k in totals}
        frames = sum(r.slip_scored_frames for r in levels)
        rows.append((name, counts, frames))
        for k in totals:
            totals[k] += counts[k]
    rows.append(("all sweeps", totals, sum(frames for _, _, frames in rows)))
    for name, counts, frames in rows:
        inc = precision_recall(*(int(c) for c in counts["incipient"]))
        gro = precision_recall(*(int(c) for c in counts["gross"]))
        lines.append(
            f"| {name} | {inc['tp'] + inc['fn']} / {gro['tp'] + gro['fn']} | "
            f"{_fmt(inc['precision'])} | {_fmt(inc['recall'])} | {_fmt(gro['precision'])} | "
            f"{_fmt(gro['recall'])} | {inc['tp'] + inc['fp']} of {frames} |"
        )
    return lines
