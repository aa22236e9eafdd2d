"""Where to take the dipole moment under pushing: candidate origins scored on the true field.

The tilt estimate is the first moment p = (1/N) sum_i (x_i - o) div_i of the divergence the
dipole sees (controller/tactile/dipole.py). With a flat contact under a grip pressure that
swings (pushing) and a tilt gradient, the zeroed divergence is a + b x on the contact, so
p = b I + a A (c - o) / N with c the contact's area centroid: the push leaks in unless o = c
(docs/ARCHITECTURE.md, "The dipole under a net press"). This tool measures how much.

For each pushing sequence of the check (sequences.py; tilt about x and y, the push 30-50%)
and each estimator configuration, the configuration's pipeline after the flow runs on the
true field (its ``flow`` hook: check.truth_flow; the texture does not matter), once per
candidate origin of the dipole moment (its ``origin`` hook), and the tilt is scored like the
check (held-out R^2 on the sequence's axis):

- ``configured``: the configuration's own rule (its ``dipole_origin``);
- ``gel centre``: o = 0;
- ``contact``: the contact's true area centroid, which only the check knows (the ideal);
- ``contact +D``: that centroid moved by D mm along the pressure gradient (the tolerance);
- ``support K``: the centroid of the soft support s_i = smoothstep(|div_i| / (K max |div|)),
  a rule an estimator could use (it knows only div).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from controller.tactile.dipole import OriginRule
from controller.tactile.estimator import TactileEstimator
from controller.tactile.settings import DipoleGrid, EstimatorConfig
from core.sensor_profile import sensor_profile
from evaluation.realgel.check import truth_flow
from evaluation.realgel.scoring import held_out_fit
from evaluation.realgel.sequences import Mechanics, SequenceSpec, mechanics
from evaluation.realgel.textures import SIZE_HW

SENSOR = "gelsight_mini"  # sets only the mm per px; the field is the truth
SUPPORT_FRACTIONS = (0.1, 0.3)
TOLERANCES_MM = (0.1, 0.2, 0.5)


def contact_centroid_mm(mech: Mechanics, mm_per_px: float) -> tuple[float, float]:
    """The contact's area centroid in frame S (mm; the image centre is the origin, pixel j's
    centre at j + 0.5 px from the image's edge, as controller.tactile.field.grid_axes_mm)."""
    mask = mech.basis.uniform
    rows, cols = np.mgrid[0 : mask.shape[0], 0 : mask.shape[1]]
    area = float(mask.sum())
    cx = float((mask * cols).sum()) / area + 0.5 - mask.shape[1] / 2
    cy = float((mask * rows).sum()) / area + 0.5 - mask.shape[0] / 2
    return cx * mm_per_px, cy * mm_per_px


def oracle_tilts(
    spec: SequenceSpec, mech: Mechanics, config: EstimatorConfig, origin: OriginRule | None
) -> np.ndarray:
    """The tilt (tau_x, tau_y) per frame (frames, 2) of ``config``'s pipeline on the true
    field ``mech`` of ``spec``, about ``origin`` (None: the configuration's own rule)."""
    config = replace(config, flow=replace(config.flow, method="dis"))
    flow = truth_flow(_MechanicsOnly(mech))
    estimator = TactileEstimator(config, sensor_profile(SENSOR), flow=flow, origin=origin)
    height, width = SIZE_HW
    # Any textured image: the truth replaces the flow on it.
    reference = np.random.default_rng(0).integers(0, 256, (height, width, 3), dtype=np.uint8)
    estimator.set_reference([reference])
    tilts = np.empty((spec.frames, 2))
    for i in range(spec.frames):
        estimate = estimator.push(reference, (i + 1) / 25.0)
        tilts[i] = estimate.tau_x, estimate.tau_y
    return tilts


@dataclass(frozen=True)
class _MechanicsOnly:
    """What TruthGridFlow reads of a rendered sequence."""

    mechanics: Mechanics


def fixed_origin(point_mm: tuple[float, float]) -> OriginRule:
    """The origin ``point_mm`` (x, y), mm in frame S, whatever the divergence."""
    o_x, o_y = float(point_mm[0]), float(point_mm[1])
    return lambda div, x, y: (o_x, o_y)


def support_centroid(fraction: float) -> OriginRule:
    """The centroid of s_i = smoothstep(|div_i| / (fraction max |div|)) (0 for div = 0)."""

    def origin(div: np.ndarray, x: np.ndarray, y: np.ndarray) -> tuple[float, float]:
        magnitude = np.abs(div)
        peak = float(magnitude.max())
        if peak == 0.0:
            return 0.0, 0.0
        t = np.clip(magnitude / (fraction * peak), 0.0, 1.0)
        s = t * t * (3.0 - 2.0 * t)
        return float(s @ x) / float(s.sum()), float(s @ y) / float(s.sum())

    return origin


def candidate_origins(spec: SequenceSpec, mech: Mechanics) -> dict[str, OriginRule | None]:
    """Every candidate origin of the module docstring, by name (None: ``configured``)."""
    centroid = contact_centroid_mm(mech, sensor_profile(SENSOR).mm_per_px)
    gradient_axis = 0 if spec.axis == "y" else 1  # a tilt about x is a pressure gradient along y
    candidates: dict[str, OriginRule | None] = {
        "configured": None,
        "gel centre": fixed_origin((0.0, 0.0)),
        "contact": fixed_origin(centroid),
    }
    for shift in TOLERANCES_MM:
        moved = list(centroid)
        moved[gradient_axis] += shift
        candidates[f"contact +{shift:g} mm"] = fixed_origin((moved[0], moved[1]))
    for fraction in SUPPORT_FRACTIONS:
        candidates[f"support {fraction:g}"] = support_centroid(fraction)
    return candidates


def origin_scores(spec: SequenceSpec, config: EstimatorConfig) -> dict[str, float]:
    """Held-out R^2 of the tilt on ``spec``'s axis for every candidate origin (module
    docstring), ``config``'s pipeline running on the true field."""
    mech = mechanics(spec)
    axis = 0 if spec.axis == "x" else 1
    truth = mech.truth[:, axis]
    return {
        name: held_out_fit(oracle_tilts(spec, mech, config, origin)[:, axis], truth).r2
        for name, origin in candidate_origins(spec, mech).items()
    }


def with_dipole_grid(config: EstimatorConfig, grid: str) -> EstimatorConfig:
    """``config`` with its dipole on ``grid``: "COLSxROWS" or "field" (the field's grid)."""
    if grid == "field":
        return replace(config, dipole_grid=None)
    cols, rows = (int(v) for v in grid.split("x"))
    return replace(config, dipole_grid=DipoleGrid(cols=cols, rows=rows))


def table(results: Sequence[tuple[str, SequenceSpec, dict[str, float]]]) -> list[str]:
    """Markdown: one row per (configuration, sequence), one column per origin."""
    names = list(results[0][2])
    lines = [
        "| configuration | sequence | " + " | ".join(names) + " |",
        "|---|---|" + "---|" * len(names),
    ]
    for label, spec, scores in results:
        cells = " | ".join(f"{scores[n]:.3f}" for n in names)
        lines.append(f"| {label} | {spec.label} | {cells} |")
    return lines
