"""Real gel captures beside rendered frames, and their appearance statistics side by side
(docs/SIMULATION.md, "Appearance").

    python -m evaluation appearance_figure [--out docs/figures/appearance.png]

The figure (PNG, matplotlib Agg) shows at native resolution: the GelSight capture with
markers beside the ``realistic`` and ``speckle`` renders of the simulated Mini (its marker
pitch, 31.5 px); the DIGIT capture beside ``realistic_digit`` and markerless ``speckle``; and
the real texture ``real:gelsight_markers_a`` at rest, warped by a 3 px twist, and their
difference. The tool prints the Markdown table of the statistics (evaluation/appearance/stats.py)
of the captures (median of each pair) and of the renders (median over ``SEEDS``).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

from core.subcommands import job_prog

matplotlib.use("Agg")
import cv2  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from core.sensor_profile import sensor_profile  # noqa: E402
from drivers.sim.render.gel_renderer import GelRenderer  # noqa: E402
from drivers.sim.render.real_texture import fit_to_size, load_capture  # noqa: E402
from drivers.sim.scenes.synthetic_sequence import phase_patterns  # noqa: E402
from evaluation.appearance.fit import capture_stats  # noqa: E402
from evaluation.appearance.stats import AppearanceStats, format_table, measure, summarise  # noqa: E402

SEEDS = (20, 21, 22, 23)
GELSIGHT_CAPTURES = ("gelsight_markers_a", "gelsight_markers_b")
DIGIT_CAPTURES = ("digit_background_a", "digit_background_b")


def mini_pitch_px() -> float:
    """The simulated GelSight Mini's marker pitch, px of its working image."""
    profile = sensor_profile("gelsight_mini")
    return profile.marker_pitch_mm / profile.mm_per_px


def render(appearance: str, pitch_px: float | None, seed: int, field=None) -> np.ndarray:
    """A 320 x 240 frame of ``appearance`` (no pixel noise: the captures show none)."""
    renderer = GelRenderer(
        pitch_px=pitch_px, rng=np.random.default_rng(seed), appearance=appearance
    )
    return renderer.render(field)


def rendered_stats(appearance: str, pitch_px: float | None) -> AppearanceStats:
    """The median statistics of reference frames over ``SEEDS``."""
    return summarise([measure(render(appearance, pitch_px, seed)) for seed in SEEDS])


def statistics_table() -> str:
    """The Markdown table of the captures' and renders' statistics."""
    pitch = mini_pitch_px()
    return format_table(
        {
            "GelSight captures": capture_stats(GELSIGHT_CAPTURES),
            "realistic": rendered_stats("realistic", pitch),
            "speckle": rendered_stats("speckle", pitch),
            "DIGIT captures": capture_stats(DIGIT_CAPTURES),
            "realistic_digit": rendered_stats("realistic_digit", None),
            "speckle, no markers": rendered_stats("speckle", None),
        }
    )


def plot(path: Path) -> None:
    """Write the figure (see the module docstring) to ``path``."""
    pitch = mini_pitch_px()
    twist = phase_patterns((240, 320), peak_px=3.0)["twist"]
    real = GelRenderer(appearance="real:gelsight_markers_a")
    at_rest, twisted = real.render(), real.render(twist)
    difference = np.clip(128 + 2 * (twisted.astype(int) - at_rest.astype(int)), 0, 255).astype(
        np.uint8
    )
    panels = [
        ("capture: gelsight_markers_a", _capture("gelsight_markers_a")),
        ("rendered: realistic", render("realistic", pitch, SEEDS[0])),
        ("rendered: speckle", render("speckle", pitch, SEEDS[0])),
        ("capture: digit_background_b (turned)", _capture("digit_background_b")),
        ("rendered: realistic_digit", render("realistic_digit", None, SEEDS[0])),
        ("rendered: speckle, no markers", render("speckle", None, SEEDS[0])),
        ("real:gelsight_markers_a at rest", at_rest),
        ("warped by a 3 px twist", twisted),
        ("difference x2 (shading static)", difference),
    ]
    fig, axes = plt.subplots(3, 3, figsize=(9.9, 8.1))
    for ax, (title, image) in zip(axes.ravel(), panels, strict=True):
        ax.imshow(cv2.cvtColor(image, cv2.COLOR_BGR2RGB), interpolation="nearest")
        ax.set_title(title, fontsize=9)
        ax.set_axis_off()
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=100)
    plt.close(fig)


def _capture(name: str) -> np.ndarray:
    return fit_to_size(load_capture(name), (240, 320))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog=job_prog("appearance_figure"),
        description="Real captures beside rendered frames (PNG) and the statistics table.",
    )
    parser.add_argument("--out", type=Path, default=Path("docs/figures/appearance.png"))
    args = parser.parse_args(argv)
    plot(args.out)
    print(f"wrote {args.out}")
    print(statistics_table())
    return 0
