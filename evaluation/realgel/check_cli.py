"""The independent real-gel check: estimators on real gel textures deformed by a half-space.

    python -m evaluation realgel_check [--estimators default,paper,dis_ultrafast,markers]
        [--textures all|NAME,...] [--amplitudes 0.4] [--frames 160] [--seed 0]
        [--lighting 0] [--shading moves|fixed] [--contact centred|varied]
        [--open-gel both|with|without] [--oracle] [--quick] [--out REPORT.md] [--json ROWS.json]

Each real capture of drivers/sim/render/real_gels/ is warped by the in-plane surface
displacement of a half-space (Boussinesq) under a tilted flat contact (evaluation/realgel/:
elastic.py, sequences.py); neither the project's gel model nor its renderer is involved.
Per texture and amplitude: tilt about x and about y, alone and while the grip pressure
swings by 30-50% (pushing), camera noise 2-4 grey levels, seeded; optionally a drifting
LED (``--lighting``) and LED shading that stays with the camera (``--shading fixed``).
Each estimator's tilt torque is calibrated by a linear fit on the first half of a sequence
and scored on the second half (R², RMSE relative to the range); also ms per frame (one
thread), the fractions of frames flagged degenerate, with exactly zero tilt, and flagged as
slipping (all sequences are slip-free). ``--oracle`` adds each estimator's pipeline run
on the true field (its flow replaced), which separates the flow's error from the dipole's.
``--contact varied`` draws the contact's aspect and position over a wider range (a plug's
face in any pose). A configuration that uses the open gel (``dipole_origin:
grasp_centroid``) is run with and without being shown it (``--open-gel``; "no open gel" rows:
an old recording zeroed on the grasp); the others ignore it and are run once.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from controller.tactile.settings import estimator_config
from core.config import ConfigError
from core.subcommands import job_prog
from evaluation.common.machine_info import cpu_model, git_revision
from evaluation.realgel.check import Entry, run_check, sequence_specs
from evaluation.realgel.check_tables import axis_table, rows_table, summary_table
from evaluation.realgel.sequences import CONTACTS
from evaluation.realgel.textures import TEXTURES

DEFAULT_ESTIMATORS = "default,paper,dis_ultrafast,markers"
QUICK_TEXTURES = ("gelsight_markers_a", "digit_background_a")


def _numbers(parser: argparse.ArgumentParser, option: str, text: str) -> list[float]:
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        parser.error(f"{option} {text!r}: expected comma-separated numbers, e.g. 0.4,1")
    if any(not 0 < v <= 20 for v in values):
        parser.error(f"{option} {text!r}: every amplitude must be in (0, 20] px")
    return values


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog=job_prog("realgel_check"), description=__doc__.splitlines()[0]
    )
    parser.add_argument(
        "--estimators",
        default=DEFAULT_ESTIMATORS,
        help="comma-separated names in configs/estimators/ or YAML paths",
    )
    parser.add_argument("--textures", default="all", help=f"all, or some of {', '.join(TEXTURES)}")
    parser.add_argument(
        "--amplitudes",
        default="0.4",
        help="peak tilt displacement, px at 320 x 240 (comma-separated)",
    )
    parser.add_argument("--frames", type=int, default=160, help="frames per sequence")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--lighting",
        type=float,
        default=0.0,
        help="LED drift amplitude, relative (0: steady light)",
    )
    parser.add_argument(
        "--shading",
        choices=("moves", "fixed"),
        default="moves",
        help="the capture's LED shading moves with the gel, or stays with the camera",
    )
    parser.add_argument(
        "--contact",
        choices=CONTACTS,
        default="centred",
        help="a near-centred contact, or one varied in aspect and position",
    )
    parser.add_argument(
        "--open-gel",
        choices=("both", "with", "without"),
        default="both",
        help="show the open gel to configurations that use it, or not, or run both",
    )
    parser.add_argument(
        "--oracle", action="store_true", help="also run each estimator's pipeline on the true field"
    )
    parser.add_argument(
        "--quick",
        action="store_true",
        help=f"two textures ({', '.join(QUICK_TEXTURES)}), 24 frames",
    )
    parser.add_argument("--out", type=Path, help="write the markdown report here")
    parser.add_argument("--json", type=Path, help="write every row as JSON here")
    args = parser.parse_args(argv)

    amplitudes = _numbers(parser, "--amplitudes", args.amplitudes)
    if args.frames < 8:
        parser.error(f"--frames {args.frames}: expected at least 8")
    if not 0.0 <= args.lighting < 0.5:
        parser.error(f"--lighting {args.lighting}: expected a relative amplitude in [0, 0.5)")
    textures = list(TEXTURES) if args.textures == "all" else args.textures.split(",")
    unknown = [t for t in textures if t not in TEXTURES]
    if unknown:
        parser.error(
            f"unknown texture {unknown[0]!r}; expected all or some of {', '.join(TEXTURES)}"
        )
    frames = args.frames
    if args.quick:
        textures = [t for t in textures if t in QUICK_TEXTURES] or textures[:2]
        frames = min(frames, 24)
    entries = []
    for name in args.estimators.split(","):
        try:
            config = estimator_config(name)
        except ConfigError as error:
            parser.error(f"--estimators: {error}")
        label = Path(name).stem if name.endswith((".yaml", ".yml")) else name
        cases = [True]
        if config.dipole_origin == "grasp_centroid":
            cases = {"both": [True, False], "with": [True], "without": [False]}[args.open_gel]
        for open_gel in cases:
            case = label if open_gel else f"{label}, no open gel"
            entries.append(Entry(case, config, open_gel=open_gel))
            if args.oracle:
                entries.append(
                    Entry(f"{case} on the true field", config, oracle=True, open_gel=open_gel)
                )

    specs = sequence_specs(
        textures, amplitudes, frames, args.seed, args.lighting, args.shading, args.contact
    )
    began = time.perf_counter()
    rows = run_check(specs, entries)
    seconds = time.perf_counter() - began
    command = "python -m evaluation realgel_check " + " ".join(
        argv if argv is not None else sys.argv[1:]
    )
    text = "\n".join(
        [
            "# Real gel textures under an independent elastic model",
            "",
            f"`{command.strip()}` — revision {git_revision()}, {cpu_model()}, one thread, "
            f"{len(specs)} sequences of {frames} frames in {seconds:.0f} s.",
            "",
            "Held-out R² of the tilt torque on the sequence's axis (fit on the first half, "
            "scored on the second); fractions are of all frames after zeroing.",
            "",
            *summary_table(rows),
            "",
            "Worst held-out R² over the textures, per tilt axis, without and with pushing:",
            "",
            *axis_table(rows),
            "",
            "## Every sequence",
            "",
            *rows_table(rows),
        ]
    )
    if args.out:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text + "\n")
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps([row.as_dict() for row in rows], indent=1))
    sys.stdout.write(text + "\n")
    return 0
