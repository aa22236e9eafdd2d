"""docs/EVALUATION.md: the tables of the calibration runs, the speed-accuracy chart and the
stability sweeps, written from measured results only."""

from __future__ import annotations

from evaluation.experiments.calibration_runs import CaseResult
from evaluation.experiments.pareto import ParetoPoint, front
from evaluation.experiments.sweeps import CONDITIONS, METHOD_AXES, LevelResult, breakdown


def calibration_table(results: list[CaseResult]) -> list[str]:
    lines = [
        "| sensor | object | axis | method | slope | RMSE (N*mm) | R^2 | baseline: slope "
        "| baseline: RMSE (N*mm) | baseline: R^2 | ours / baseline RMSE | frames |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for result in results:
        for axis in ("x", "y", "z"):
            if (axis, "ours") not in result.fits:
                continue
            ours, base = result.fits[(axis, "ours")], result.fits[(axis, "baseline")]
            method = "NHHD" if axis == "z" else "dipole"
            ratio = ours.rmse / base.rmse if base.rmse > 0 else float("nan")
            lines.append(
                f"| {result.case.sensor} | {_object(result)} | tau_{axis} | {method} "
                f"| {ours.slope:.4g} | {ours.rmse * 1e3:.3f} | {ours.r2:.4f} "
                f"| {base.slope:.4g} | {base.rmse * 1e3:.3f} | {base.r2:.4f} | {ratio:.2f} "
                f"| {ours.samples} |"
            )
    return lines


def _object(result: CaseResult) -> str:
    """The object, with the real capture it was rendered on if not the nominal look."""
    look = result.case.appearance
    return result.case.shape if look is None else f"{result.case.shape} on {look}"


def pareto_table(points: list[ParetoPoint]) -> list[str]:
    on_front = {p.label for p in front(points)}
    on_any_front = {p.label for p in front(points, eligible_only=False)}
    datasets = list(points[0].rmse_by_dataset)
    lines = [
        "| configuration | median ms | p90 ms | tilt RMSE (N*mm) | "
        + " | ".join(f"RMSE {name}" for name in datasets)
        + " | worst R^2 | worst real-gel R^2 | slip recall | on the front | on the front of all |",
        "|---|---|---|---|" + "---|" * len(datasets) + "---|---|---|---|---|",
    ]
    for p in sorted(points, key=lambda p: p.latency_ms):
        per_dataset = " | ".join(f"{p.rmse_by_dataset[name]:.3f}" for name in datasets)
        lines.append(
            f"| {p.label} | {p.latency_ms:.2f} | {p.p90_ms:.2f} | **{p.rmse_nmm:.3f}** | "
            f"{per_dataset} | {p.r2:.4f} | {p.realgel_r2:.3f} | "
            f"{'-' if p.slip_recall is None else f'{p.slip_recall:.2f}'} | "
            f"{'yes' if p.label in on_front else ''} | "
            f"{'yes' if p.label in on_any_front else ''} |"
        )
    return lines


def sweep_tables(results: dict[str, list[LevelResult]]) -> list[str]:
    methods = list(METHOD_AXES)
    lines = [
        "Breakdown level per method (first level, walking away from nominal, where R^2 < 0.9 "
        "or RMSE/peak doubles over nominal; 'below / above' when the nominal is inside the "
        "sweep; '-' none in the sweep):",
        "",
        "| condition | nominal | " + " | ".join(methods) + " |",
        "|---|---|" + "---|" * len(methods),
    ]
    for condition in CONDITIONS:
        levels = results[condition.name]
        nominal_label = condition.level_label(condition.levels.index(condition.nominal))
        cells = [breakdown(condition, levels, m) for m in methods]
        lines.append(f"| {condition.name} | {nominal_label} | " + " | ".join(cells) + " |")
    lines += ["", "R^2 and RMSE (N*mm) per level:", ""]
    for condition in CONDITIONS:
        unit = f" ({condition.unit})" if condition.unit else ""
        lines += [
            f"**{condition.name}**{unit}",
            "",
            "| level | " + " | ".join(methods) + " |",
            "|---|" + "---|" * len(methods),
        ]
        for i, result in enumerate(results[condition.name]):
            cells = [f"{result.r2[m]:.3f} / {result.rmse_nmm[m]:.2f}" for m in methods]
            lines.append(f"| {condition.level_label(i)} | " + " | ".join(cells) + " |")
        lines.append("")
    return lines
