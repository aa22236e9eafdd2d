"""The insertion scene's camera effects measured on the real captures (docs/SIMULATION.md,
"The sensor"): the marker edge width, channel means and noise statistic of the two GelSight
captures with markers, against the ``realistic`` gel rendered with optical blurs of
increasing sigma (the median over seeds 20-23, as the appearance fit's figure).

    python -m evaluation sensor_levels [--blur 0,0.3,0.5,0.7]
"""

from __future__ import annotations

import argparse

import numpy as np

from controller.cli.support import number_list, run_tool
from drivers.sim.render.gel_renderer import GelRenderer
from drivers.sim.render.image_effects import ImageEffects
from drivers.sim.render.real_texture import load_capture
from evaluation.appearance.stats import measure, table_rows

CAPTURES = ("gelsight_markers_a", "gelsight_markers_b")
KEYS = ("marker edge 10-90 % px", "mean B", "mean G", "mean R", "noise")
SEEDS = (20, 21, 22, 23)
MINI_PITCH_PX = 31.5


def rows(blurs: list[float]) -> list[str]:
    """Markdown rows: each capture's statistics, then the render's per blur sigma."""
    out = ["| image | " + " | ".join(KEYS) + " |", "|---" * (len(KEYS) + 1) + "|"]
    for name in CAPTURES:
        stats = table_rows(measure(load_capture(name)))
        out.append(f"| {name} | " + " | ".join(f"{stats[k]:.3f}" for k in KEYS) + " |")
    for sigma in blurs:
        per_seed = [
            table_rows(
                measure(
                    GelRenderer(
                        pitch_px=MINI_PITCH_PX,
                        effects=ImageEffects(blur_sigma_px=sigma),
                        rng=np.random.default_rng(seed),
                        appearance="realistic",
                    ).render()
                )
            )
            for seed in SEEDS
        ]
        medians = [float(np.median([r[k] for r in per_seed])) for k in KEYS]
        out.append(
            f"| realistic, blur {sigma:g} px | " + " | ".join(f"{v:.3f}" for v in medians) + " |"
        )
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--blur",
        type=number_list(0.0, 20.0, "px"),
        default=(0.0, 0.3, 0.5, 0.7),
        help="blur sigmas, px, comma-separated",
    )
    args = parser.parse_args(argv)

    def body() -> int:
        print("\n".join(rows(list(args.blur))))
        return 0

    return run_tool("sensor_levels", body)
