"""Fitting a ``RealisticLook`` (drivers/sim/render/realistic.py) to real captures.

The target is the median of the captures' statistics (evaluation/appearance/stats.py), measured at
the working size. Each round renders reference frames of the look at that size with
``SEEDS`` (rounded to uint8) and averages their statistics; then:

* **texture and pixel noise**: the rendered power (RMS squared) in each octave band, and
  the noise statistic squared, are their values without texture or noise plus a linear mix
  of the texture's band powers and the noise variance (independent noises; the measuring
  filters overlap, and the noise statistic sees the finest texture too). One probe render
  per band (that band alone at ``PROBE_RMS``) and one with ``PROBE_NOISE_GREY`` of pixel
  noise give the mixing matrix; the band powers and the noise variance are then the
  non-negative least squares solution that makes the totals match the target's, each
  statistic's error relative to its target;
* **markers** (diameter, ink, edge sigma) and **lighting** (channel means and spreads):
  each multiplied by target / rendered of the statistic it sets (diameter, darkness, 10-90 %
  edge width, mean_bgr, shading_spread_bgr); the channel correlations moved by target -
  rendered.

Marker parameters are kept when the captures have no markers. ``lattice_jitter_px`` and
``light_scale_px`` are not fitted here (docs/SIMULATION.md says how they were set). The pixel
noise is not part of the look: the renderer's caller adds it as an image effect
(``ImageEffects.noise_grey``); the fitted value is the captures' level.
"""

from __future__ import annotations

import argparse
import dataclasses
from dataclasses import dataclass

import numpy as np
from scipy.optimize import nnls
from scipy.spatial import cKDTree

from core.subcommands import job_prog
from drivers.sim.render.gel_renderer import GelRenderer
from drivers.sim.render.image_effects import ImageEffects
from drivers.sim.render.real_texture import REAL_GELS_DIR, fit_to_size, load_capture
from drivers.sim.render.realistic import REALISTIC, REALISTIC_DIGIT, RealisticLook
from evaluation.appearance.stats import AppearanceStats, format_table, measure, summarise

SEEDS = (0, 1, 2, 3)
ROUNDS = 5
PROBE_RMS = 0.01
PROBE_NOISE_GREY = 1.0
SHAPE_HW = (240, 320)


def capture_stats(names: tuple[str, ...], shape_hw: tuple[int, int] = SHAPE_HW) -> AppearanceStats:
    """The median statistics of the shipped captures ``names`` at the working size."""
    return summarise([measure(fit_to_size(load_capture(n), shape_hw)) for n in names])


def rendered_stats(
    look: RealisticLook,
    pitch_px: float | None,
    seeds: tuple[int, ...] = SEEDS,
    noise_grey: float = 0.0,
    shape_hw: tuple[int, int] = SHAPE_HW,
) -> AppearanceStats:
    """The mean statistics of reference frames of ``look`` rendered with ``seeds``."""
    stats = []
    for seed in seeds:
        renderer = GelRenderer(
            width_px=shape_hw[1],
            height_px=shape_hw[0],
            pitch_px=pitch_px,
            effects=ImageEffects(noise_grey=noise_grey),
            rng=np.random.default_rng(seed),
            appearance=look,
        )
        stats.append(dataclasses.asdict(measure(renderer.render())))
    mean = {}
    for key, value in stats[0].items():
        column = np.mean([s[key] for s in stats], axis=0)
        mean[key] = tuple(float(v) for v in column) if isinstance(value, tuple) else column
    return AppearanceStats(**mean)


def fit_look(
    target: AppearanceStats, start: RealisticLook, pitch_px: float | None, rounds: int = ROUNDS
) -> tuple[RealisticLook, float]:
    """The look and the pixel noise (grey levels) whose rendered statistics match ``target``
    (see the module docstring); ``pitch_px`` is the lattice to render (the captures')."""
    look = start
    for _ in range(rounds):
        bands, noise_grey = _texture_and_noise(look, target, pitch_px)
        look = dataclasses.replace(look, texture_band_rms=bands)
        got = rendered_stats(look, pitch_px, noise_grey=noise_grey)
        changes: dict[str, object] = {
            "light_mean_bgr": _scaled(look.light_mean_bgr, target.mean_bgr, got.mean_bgr),
            "light_spread_bgr": _scaled(
                look.light_spread_bgr, target.shading_spread_bgr, got.shading_spread_bgr
            ),
            "light_correlation_bg_br_gr": tuple(
                float(np.clip(p + t - g, -0.95, 0.95))
                for p, t, g in zip(
                    look.light_correlation_bg_br_gr,
                    target.shading_correlation_bg_br_gr,
                    got.shading_correlation_bg_br_gr,
                    strict=True,
                )
            ),
        }
        if pitch_px is not None and target.marker_count > 0:
            diameter, ink, edge = _scaled(
                (look.marker_diameter_px, look.marker_ink, look.marker_edge_sigma_px),
                (target.marker_diameter_px, target.marker_darkness, target.marker_edge_10_90_px),
                (got.marker_diameter_px, got.marker_darkness, got.marker_edge_10_90_px),
            )
            changes.update(
                marker_diameter_px=diameter, marker_ink=min(ink, 0.99), marker_edge_sigma_px=edge
            )
        look = _valid(look, changes)
    return look, noise_grey


def _texture_and_noise(
    look: RealisticLook, target: AppearanceStats, pitch_px: float | None
) -> tuple[tuple[float, ...], float]:
    count = len(look.texture_band_rms)

    def power(bands: tuple[float, ...], noise_grey: float = 0.0) -> np.ndarray:
        probe = dataclasses.replace(look, texture_band_rms=bands)
        got = rendered_stats(probe, pitch_px, noise_grey=noise_grey)
        return np.square([*got.band_rms_grey, got.noise_grey])

    base = power((0.0,) * count)
    probes = [tuple(PROBE_RMS * (j == k) for j in range(count)) for k in range(count)]
    mixing = np.stack(
        [(power(bands) - base) / PROBE_RMS**2 for bands in probes]
        + [power((0.0,) * count, PROBE_NOISE_GREY) - base],
        axis=1,
    )
    goal = np.square([*target.band_rms_grey, target.noise_grey])
    wanted = np.maximum(goal - base, 0.0)
    # relative errors: each statistic counts alike, whatever its power
    solution, _ = nnls(np.maximum(mixing, 0.0) / goal[:, None], wanted / goal)
    bands = tuple(float(v) for v in np.sqrt(solution[:count]))
    return bands, float(np.sqrt(solution[count])) * PROBE_NOISE_GREY


def _scaled(values, targets, got) -> tuple[float, ...]:
    return tuple(
        float(v * t / g) if g > 0 else float(v)
        for v, t, g in zip(values, targets, got, strict=True)
    )


def _valid(look: RealisticLook, changes: dict[str, object]) -> RealisticLook:
    """The look with ``changes``, without a correlation change that is not a valid matrix."""
    try:
        return dataclasses.replace(look, **changes)
    except ValueError:
        changes.pop("light_correlation_bg_br_gr")
        return dataclasses.replace(look, **changes)


def lattice_fit(positions_px: np.ndarray) -> tuple[float, float, float]:
    """(pitch_x, pitch_y, jitter) px of marker positions (N, 2) (x, y) given in whole px: the
    best affine lattice's steps along its two axes, and the largest offset of a uniform
    jitter that explains the residuals (their mean square per axis less the rounding's
    1/12 px^2, times 3: a uniform offset of up to j has a mean square of j^2 / 3)."""
    _, nearest = cKDTree(positions_px).query(positions_px, k=5)
    steps = positions_px[nearest[:, 1:]] - positions_px[:, None, :]
    along_x = np.abs(steps[..., 0]) > np.abs(steps[..., 1])
    pitch_guess = (
        np.median(np.abs(steps[..., 0])[along_x]),
        np.median(np.abs(steps[..., 1])[~along_x]),
    )
    index = np.rint((positions_px - positions_px.min(axis=0)) / pitch_guess)
    design = np.column_stack([index, np.ones(len(index))])
    coefficients, *_ = np.linalg.lstsq(design, positions_px, rcond=None)
    residual = positions_px - design @ coefficients
    variance = max(float(np.mean(residual**2)) - 1.0 / 12.0, 0.0)
    pitch_x, pitch_y = np.hypot(*coefficients[:2].T)
    return float(pitch_x), float(pitch_y), float(np.sqrt(3.0 * variance))


@dataclass(frozen=True)
class CaptureSet:
    """Captures to fit one look to, the look to start from, and whether they have markers
    (their positions, for the lattice, in ``<capture>.csv`` beside the images)."""

    captures: tuple[str, ...]
    start: RealisticLook
    has_markers: bool


CAPTURE_SETS = {
    "realistic": CaptureSet(("gelsight_markers_a", "gelsight_markers_b"), REALISTIC, True),
    "realistic_digit": CaptureSet(
        ("digit_background_a", "digit_background_b"), REALISTIC_DIGIT, False
    ),
}
CHECK_SEEDS = (10, 11, 12, 13)


def fit_capture_set(name: str) -> tuple[RealisticLook, float, AppearanceStats, AppearanceStats]:
    """Fit the look ``name`` of ``CAPTURE_SETS``: (look, noise_grey, the captures' statistics,
    the fitted look's on ``CHECK_SEEDS``, seeds the fit did not use)."""
    spec = CAPTURE_SETS[name]
    target = capture_stats(spec.captures)
    start, pitch_px = spec.start, None
    if spec.has_markers:
        lattices = [
            lattice_fit(np.loadtxt(REAL_GELS_DIR / f"{c}.csv", delimiter=",", skiprows=1)[:, :2])
            for c in spec.captures
        ]
        pitch_x, pitch_y, jitter = np.median(lattices, axis=0)
        pitch_px = float(np.sqrt(pitch_x * pitch_y))
        start = dataclasses.replace(start, lattice_jitter_px=round(float(jitter), 2))
    look, noise_grey = fit_look(target, start, pitch_px)
    return look, noise_grey, target, rendered_stats(look, pitch_px, CHECK_SEEDS, noise_grey)


def look_source(name: str, look: RealisticLook) -> str:
    """Python source of the look, numbers to 4 significant digits."""

    def number(value: float) -> str:
        return f"{value:.4g}"

    lines = [f"{name.upper()} = RealisticLook("]
    for field in dataclasses.fields(look):
        value = getattr(look, field.name)
        text = (
            "(" + ", ".join(number(v) for v in value) + ")"
            if isinstance(value, tuple)
            else number(value)
        )
        lines.append(f"    {field.name}={text},")
    return "\n".join([*lines, ")"])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog=job_prog("fit_appearance"),
        description="Fit the realistic looks to the shipped real captures and print them "
        "(paste into drivers/sim/render/realistic.py).",
    )
    parser.add_argument(
        "looks", nargs="*", metavar="LOOK", help=f"looks to fit: {', '.join(CAPTURE_SETS)} (all)"
    )
    args = parser.parse_args(argv)
    unknown = sorted(set(args.looks) - set(CAPTURE_SETS))
    if unknown:
        parser.error(f"unknown look {unknown[0]!r}; expected one of {', '.join(CAPTURE_SETS)}")
    for name in args.looks or list(CAPTURE_SETS):
        look, noise_grey, target, check = fit_capture_set(name)
        print(look_source(name, look))
        print(f"# captures' pixel noise: {noise_grey:.3g} grey levels")
        print(format_table({"captures": target, f"{name} (check seeds)": check}))
    return 0
