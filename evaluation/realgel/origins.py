"""Where to take the dipole moment under pushing: candidate origins scored on the true field.

The tilt estimate is the first moment p = (1/N) sum_i (x_i - o) div_i of the divergence the
dipole sees (controller/tactile/dipole.py). With a flat contact under a grip pressure that
swings (pushing) and a tilt gradient, the zeroed divergence is a + b x on the contact, so
p = b I + a A (c - o) / N with c the contact's area centroid: the push leaks in unless o = c
(docs/ARCHITECTURE.md, "The dipole under a net press"). This tool measures how much.

For each pushing sequence of the check (sequences.py; tilt about x and y, the push 30-50%)
and each estimator configuration, the configuration's pipeline after the flow runs on the
true field (check.TruthGridFlow; the texture does not matter), and the divergence it hands
the dipole is recorded. The tilt is then taken about each candidate origin and scored like
the check (held-out R^2 on the sequence's axis):

- ``configured``: the configuration's own rule (its ``dipole_origin``);
- ``gel centre``: o = 0;
- ``support K``: the centroid of the soft support s_i = smoothstep(|div_i| / (K max |div|)),
  a rule an estimator could use (it knows only div);
- ``contact``: the contact's true area centroid, which only the check knows (the ideal);
- ``contact +D``: that centroid moved by D mm along the pressure gradient (the tolerance).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np

from controller.tactile.estimator import TactileEstimator
from controller.tactile.settings import DipoleGrid, EstimatorConfig, field_grid
from core.sensor_profile import sensor_profile
from evaluation.realgel.check import TruthGridFlow
from evaluation.realgel.scoring import held_out_fit
from evaluation.realgel.sequences import Mechanics, SequenceSpec, mechanics
from evaluation.realgel.textures import SIZE_HW

SENSOR = "gelsight_mini"  # sets only the mm per px; the field is the truth
SUPPORT_FRACTIONS = (0.1, 0.3)
TOLERANCES_MM = (0.1, 0.2, 0.5)

Origin = Callable[[np.ndarray, np.ndarray, np.ndarray], tuple[float, float]]


@dataclass(frozen=True)
class OracleRun:
    """One sequence through one configuration on the true field: the dipole's divergence per
    frame ``div`` (frames, rows, cols), its grid ``x``/``y`` (flattened, mm, frame S), the
    configuration's own tilt ``configured`` (frames, 2), the truth (frames, 2), the contact's
    area centroid ``centroid`` (mm, frame S) and the axis index of the tilt (0: x)."""

    div: np.ndarray
    x: np.ndarray
    y: np.ndarray
    configured: np.ndarray
    truth: np.ndarray
    centroid: tuple[float, float]
    axis: int


def contact_centroid_mm(mech: Mechanics, mm_per_px: float) -> tuple[float, float]:
    """The contact's area centroid in frame S (mm; the image centre is the origin, pixel j's
    centre at j + 0.5 px from the image's edge, as controller.tactile.field.grid_axes_mm)."""
    mask = mech.basis.uniform
    rows, cols = np.mgrid[0 : mask.shape[0], 0 : mask.shape[1]]
    area = float(mask.sum())
    cx = float((mask * cols).sum()) / area + 0.5 - mask.shape[1] / 2
    cy = float((mask * rows).sum()) / area + 0.5 - mask.shape[0] / 2
    return cx * mm_per_px, cy * mm_per_px


def oracle_run(spec: SequenceSpec, config: EstimatorConfig) -> OracleRun:
    """Run ``config``'s pipeline on ``spec``'s true field, recording the dipole's input."""
    config = replace(config, flow=replace(config.flow, method="dis"))
    estimator = TactileEstimator(config, sensor_profile(SENSOR))
    height, width = SIZE_HW
    # Any textured image builds the (unused) flow; the truth replaces it below.
    reference = np.random.default_rng(0).integers(0, 256, (height, width, 3), dtype=np.uint8)
    estimator.set_reference([reference])
    mech = mechanics(spec)
    estimator._grid_flow = TruthGridFlow(_MechanicsOnly(mech), *field_grid(config, height, width))
    dipole = estimator._dipole
    recorded = []

    def record(div: np.ndarray):
        recorded.append(div.copy())
        return dipole(div)

    estimator._dipole = record
    configured = np.empty((spec.frames, 2))
    for i in range(spec.frames):
        estimate = estimator.push(reference, (i + 1) / 25.0)
        configured[i] = estimate.tau_x, estimate.tau_y
    return OracleRun(
        np.array(recorded),
        dipole._x.copy(),
        dipole._y.copy(),
        configured,
        mech.truth,
        contact_centroid_mm(mech, estimator.profile.mm_per_px),
        0 if spec.axis == "x" else 1,
    )


@dataclass(frozen=True)
class _MechanicsOnly:
    """What TruthGridFlow reads of a rendered sequence."""

    mechanics: Mechanics


def support_centroid(fraction: float) -> Origin:
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


def origin_scores(run: OracleRun) -> dict[str, float]:
    """Held-out R^2 of the tilt on the run's axis for every candidate origin (module
    docstring)."""
    truth = run.truth[:, run.axis]
    scores = {"configured": held_out_fit(run.configured[:, run.axis], truth).r2}
    centroid = np.asarray(run.centroid)
    gradient_axis = 1 - run.axis  # a tilt about x is a pressure gradient along y
    fixed = {"gel centre": np.zeros(2), "contact": centroid}
    for shift in TOLERANCES_MM:
        moved = centroid.copy()
        moved[gradient_axis] += shift
        fixed[f"contact +{shift:g} mm"] = moved
    rules: dict[str, Origin] = {f"support {k:g}": support_centroid(k) for k in SUPPORT_FRACTIONS}
    div = run.div.reshape(len(run.div), -1)
    n = div.shape[1]
    for name, point in fixed.items():
        p = np.stack([(run.x - point[0]) @ div.T, (run.y - point[1]) @ div.T], axis=1) / n
        scores[name] = _score(p, run.axis, truth)
    for name, rule in rules.items():
        p = np.empty((len(div), 2))
        for i, d in enumerate(div):
            ox, oy = rule(d, run.x, run.y)
            p[i] = (run.x - ox) @ d / n, (run.y - oy) @ d / n
        scores[name] = _score(p, run.axis, truth)
    return scores


def _score(p: np.ndarray, axis: int, truth: np.ndarray) -> float:
    """R^2 of the tilt [p_y, -p_x] on ``axis`` (dipole.DipoleMoment.tilt_torque_raw)."""
    tilt = p[:, 1] if axis == 0 else -p[:, 0]
    return held_out_fit(tilt, truth).r2


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
