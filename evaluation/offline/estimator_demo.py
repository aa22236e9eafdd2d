"""The offline estimator demo on a synthetic tactile sequence the project renders itself.

Renders a marker-gel image sequence (tilt about x, tilt about y, twist, shear; see
drivers/sim/scenes/synthetic_sequence.py) into OUT/frames/, runs the offline estimator on it
exactly as on a recording (controller/cli/estimate.py), and writes OUT/estimates.csv,
OUT/truth.csv and OUT/estimates.png, then prints how well each estimate follows its pattern
(correlation), for the dipole/NHHD estimates and the FingerVision baseline side by side.
Run by ``make estimator-demo`` (python -m evaluation demo).
"""

from __future__ import annotations

import argparse
import csv
from pathlib import Path

import cv2
import numpy as np

from controller.cli.estimate import estimate_file
from controller.cli.outputs import atomic_text, check_output_folder
from controller.cli.support import SEED, resolved_config_path, run_tool
from controller.tactile import estimator_for_sensor
from drivers.sim.render.marker_images import MarkerImageRenderer
from drivers.sim.scenes.synthetic_sequence import PHASES, demo_sequence
from evaluation.offline.plotting import plot_series_against_truth

SENSOR = "gelsight_mini"

# (estimate column, phase, baseline column or None)
AXES = (
    ("tau_x", "tilt_x", "fv_tau_x"),
    ("tau_y", "tilt_y", "fv_tau_y"),
    ("tau_z", "twist", "fv_tau_z"),
    ("shear_x", "shear", None),
)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("out/demo"))
    parser.add_argument(
        "--method", default=None, help="estimator configuration (default: the Mini profile's)"
    )
    parser.add_argument("--seed", type=SEED, default=7)
    args = parser.parse_args(argv)
    return run_tool("demo", lambda: demo(args))


def demo(args: argparse.Namespace) -> int:
    method = estimator_for_sensor(SENSOR, args.method).config_name
    check_output_folder(args.out, [resolved_config_path(method, "estimators")], option="--out")
    frames_dir = args.out / "frames"
    frames_dir.mkdir(parents=True, exist_ok=True)
    for old in frames_dir.glob("*.png"):
        old.unlink()
    renderer = MarkerImageRenderer(rng=np.random.default_rng(args.seed))
    sequence = demo_sequence()
    for index, frame in enumerate(sequence):
        cv2.imwrite(
            str(frames_dir / f"frame_{index:04d}.png"), renderer.render(frame.displacement_px)
        )
    with atomic_text(args.out / "truth.csv", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["frame", "time_s", *PHASES[1:]])
        for index, f in enumerate(sequence):
            writer.writerow(
                [index, f"{f.t_s:.4f}", *(f.amplitude if f.phase == p else 0.0 for p in PHASES[1:])]
            )
    print(f"demo: rendered {len(sequence)} synthetic frames into {frames_dir}")

    out_csv = args.out / "estimates.csv"
    estimate_file(frames_dir, out_csv, reference="0:5", sensor=SENSOR, method=method, fps=25.0)
    with out_csv.open() as handle:
        rows = list(csv.DictReader(handle))
    column = {key: np.array([float(r[key]) for r in rows]) for key in rows[0]}
    truth = {
        p: np.array([f.amplitude if f.phase == p else 0.0 for f in sequence]) for p in PHASES[1:]
    }

    phase = np.array([f.phase for f in sequence])
    print(f"demo: wrote {out_csv}")
    print("  Each estimate is scaled to its pattern by least squares within that pattern's phase;")
    print("  r: correlation there; cross-talk: largest scaled response during the other phases.")
    print("  The twist and shear patterns move the contact; the gel's torque and force on the")
    print("  object oppose that motion, so ours reads r = -1 there (docs/ARCHITECTURE.md).")
    panels = []
    for est, name, baseline in AXES:
        estimates = {}
        for label, col in (("ours", est), ("FingerVision", baseline)):
            if col is None:
                continue
            own = phase == name
            values, target = column[col], truth[name]
            scale = float(values[own] @ target[own] / max(values[own] @ values[own], 1e-300))
            r = np.corrcoef(values[own], target[own])[0, 1]
            leak = float(np.abs(scale * values[(~own) & (phase != "rest")]).max())
            print(f"  {col:9s} vs {name:7s} ({label:12s}): r = {r:+.3f}   cross-talk = {leak:.2f}")
            estimates[f"{label} {col} (x{scale:.3g})"] = scale * values
        panels.append((name, truth[name], estimates))
    median_ms = float(np.median(column["latency_ms"]))
    print(f"  median estimator latency {median_ms:.2f} ms/frame (config '{method}')")
    png = args.out / "estimates.png"
    title = f"Synthetic sequence, estimator '{method}' (each series scaled within its phase)"
    plot_series_against_truth(column["time_s"], panels, png, title)
    print(f"demo: wrote {png}")
    return 0
