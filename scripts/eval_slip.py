#!/usr/bin/env python3
"""Precision, recall and delay of the estimator's slip flags on the simulated gel.

Each sequence drives the gel model (drivers/sim/gel) with a grip force and a wrench per
frame, renders the marker-gel image (seeded, plus seeded camera noise), and runs the
estimator on it, zeroed on the grasp's first frame, exactly as on hardware. The flags are
scored per frame against the model's truth:

* incipient slip: at least ``INCIPIENT_SLIP_FRACTION`` (20%) of the loaded cells at the
  friction limit, or gross slip. The outermost ring of the footprint, where the gel's free
  edge lets the pressure fall to zero, slips under almost any shear (9% of a plate's cells
  at a tenth of its friction capacity), so the bar must sit above that ring; 20% is the
  first level where slip has spread past it, and in Cattaneo-Mindlin terms (slip area
  fraction 1 - (1 - Q / mu P)^(2/3)) it is reached at about 28% of the friction capacity.
* gross slip: the model's ``gross_slip`` (the load exceeds what friction can hold).

Positive sequences ramp a load from stick through partial slip to 1.15 times the friction
capacity (found by bisection for each object and grip), hold it while the object slides
(its footprint moves: 0.05 mm or 0.004 rad per frame), release it and rest: shear along +x,
shear along -y, twist, shear with twist, and a ramp to 75% that holds in partial slip.
Negative sequences must not fire: tilt about x and y up to 80% of the lift-off torque and
back through zero, the grip force doubled and restored, and a tilt on top of a stuck shear
(15% of capacity). Objects: the plate and the square peg. Frames come at the sensor's rate.

Delay: frames from the first true frame to the first flagged one (negative: flagged early;
"missed": never). The re-zero check counts gross-slip sequences whose policy recommends a
re-zero after the release, and frames where it recommends one while loaded (more than 10%
of capacity), which must be zero.

    python scripts/eval_slip.py [--method default] [--grips 10,7,14] [--seed 11]
        [--noise-grey 1.0] [--objects plate,square_peg] [--quick] [--out docs/SLIP_EVAL.md]

The thresholds in configs/estimators/*.yaml were chosen on the 10 N grip; the 7 N and
14 N grips (other friction capacities, other seeds) are held out.
"""

from __future__ import annotations

import argparse
import platform
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from controller.config import load_config, sensor_profile
from controller.tactile.estimator import TactileEstimator
from controller.tactile.settings import EstimatorConfig, estimator_config
from drivers.sim.gel.model import GelModel, GelState, Wrench
from drivers.sim.gel.profile import SHAPES, GelProfile
from drivers.sim.marker_images import MarkerImageRenderer

ROOT = Path(__file__).resolve().parents[1]
GEL_PROFILE = ROOT / "configs" / "sensors" / "gelsight_mini_gel.yaml"
SENSOR = "gelsight_mini"
OBJECTS = ("plate", "square_peg")
INCIPIENT_SLIP_FRACTION = 0.2
LOADED_FRACTION = 0.1  # of capacity: a re-zero recommended above this is "under load"
SLIDE_M_PER_FRAME = 0.05e-3
TURN_RAD_PER_FRAME = 0.004


@dataclass(frozen=True)
class Capacity:
    """What the grasp holds: in-plane force (N) and torque (N*m) before gross slip, and the
    tilt torques (N*m) at which the face starts to lift off."""

    force_n: float
    torque_nm: float
    tilt_x_nm: float
    tilt_y_nm: float


@dataclass(frozen=True)
class Sequence:
    shape: str
    name: str
    positive: bool
    grips_n: tuple[float, ...]
    wrenches: tuple[Wrench, ...]


@dataclass(frozen=True)
class Frame:
    """One frame's truth and flags."""

    incipient: bool
    gross: bool
    loaded: bool
    flag_incipient: bool
    flag_gross: bool
    rezero: bool


def _bisect(holds, high: float, iterations: int = 24) -> float:
    low = 0.0
    for _ in range(iterations):
        middle = 0.5 * (low + high)
        low, high = (middle, high) if holds(middle) else (low, middle)
    return low


def capacity(model: GelModel, grip_n: float) -> Capacity:
    def solve(**load: float) -> GelState:
        return model.solve(grip_n, Wrench(**load))

    return Capacity(
        force_n=_bisect(lambda f: not solve(fx=f).tangential.gross_slip, 5.0 * grip_n),
        torque_nm=_bisect(lambda t: not solve(tau_z=t).tangential.gross_slip, 0.05 * grip_n),
        tilt_x_nm=_bisect(lambda t: not solve(tau_x=t).lifted_off, 0.05 * grip_n),
        tilt_y_nm=_bisect(lambda t: not solve(tau_y=t).lifted_off, 0.05 * grip_n),
    )


def _ramp(start: float, stop: float, frames: int) -> list[float]:
    return list(np.linspace(start, stop, frames + 1)[1:])


def _up_hold_down(peak: float, up: int = 24, hold: int = 8, down: int = 12) -> list[float]:
    """Load profile (fraction of the peak): rest, ramp up, hold, release, rest long enough
    for the re-zero policy to settle."""
    return [0.0] * 3 + _ramp(0, peak, up) + [peak] * hold + _ramp(peak, 0, down) + [0.0] * 13


def _there_and_back(peak: float, frames: int = 12) -> list[float]:
    return (
        [0.0] * 3
        + _ramp(0, peak, frames)
        + _ramp(peak, -peak, 2 * frames)
        + _ramp(-peak, 0, frames)
        + [0.0] * 3
    )


def sequences(shape: str, grip_n: float, cap: Capacity) -> list[Sequence]:
    """The positive sequences first, then the negative ones (see the module docstring)."""
    f, t = cap.force_n, cap.torque_nm

    def seq(name: str, positive: bool, loads: list[dict], grips: list[float] | None = None):
        grips = grips or [grip_n] * len(loads)
        wrenches = tuple(Wrench(**load) for load in loads)
        return Sequence(shape, name, positive, tuple(grips), wrenches)

    full = _up_hold_down(1.15)
    tilt = _there_and_back(0.8)
    double = _up_hold_down(1.0, 12, 6, 12)
    settle = 10  # frames to put on the stuck shear before tilting
    on_shear = [(0.15 * f * min(1.0, i / settle), 0.0) for i in range(settle)]
    on_shear += [(0.15 * f, a) for a in tilt]
    return [
        seq("shear +x", True, [{"fx": a * f} for a in full]),
        seq("shear -y", True, [{"fy": -a * f} for a in full]),
        seq("twist", True, [{"tau_z": a * t} for a in full]),
        seq(
            "shear+twist",
            True,
            [{"fx": -0.6 * a * f, "fy": 0.6 * a * f, "tau_z": 0.3 * a * t} for a in full],
        ),
        seq("partial hold", True, [{"fx": a * f} for a in _up_hold_down(0.75, 20, 12, 12)]),
        seq("tilt x", False, [{"tau_x": a * cap.tilt_x_nm} for a in tilt]),
        seq("tilt y", False, [{"tau_y": a * cap.tilt_y_nm} for a in tilt]),
        seq("grip x2", False, [{}] * len(double), [grip_n * (1 + a) for a in double]),
        seq("tilt on shear", False, [{"fx": s, "tau_x": a * cap.tilt_x_nm} for s, a in on_shear]),
    ]


def _full_res(field_px: np.ndarray, width: int, height: int) -> np.ndarray:
    return cv2.resize(field_px.astype(np.float32), (width, height), interpolation=cv2.INTER_LINEAR)


def run_sequence(
    sequence: Sequence,
    model: GelModel,
    cap: Capacity,
    config: EstimatorConfig,
    renderer: MarkerImageRenderer,
    rng: np.random.Generator,
    noise_grey: float,
) -> list[Frame]:
    """Drive the model through the sequence (the object slides while in gross slip), render
    and estimate each frame."""
    profile = sensor_profile(SENSOR)
    width, height = profile.width_px, profile.height_px

    clean: dict[bytes, np.ndarray] = {}  # rest and frozen frames repeat a field: render once

    def image(state: GelState) -> np.ndarray:
        key = state.field_px.tobytes()
        if key not in clean:
            field = _full_res(state.field_px, width, height)
            clean[key] = renderer.render(field).astype(np.float32)
        noisy = clean[key] + noise_grey * rng.standard_normal(clean[key].shape, dtype=np.float32)
        return np.clip(noisy + 0.5, 0, 255).astype(np.uint8)

    estimator = TactileEstimator(config, profile)
    estimator.set_reference(image(model.solve(sequence.grips_n[0], Wrench())))
    offset, angle, frames = np.zeros(2), 0.0, []
    for index, (grip, wrench) in enumerate(zip(sequence.grips_n, sequence.wrenches, strict=True)):
        state = model.solve(grip, wrench, offset_m=(offset[0], offset[1]), angle_rad=angle)
        estimate = estimator.push(image(state), index / profile.fps_hz)
        force = float(np.hypot(wrench.fx, wrench.fy))
        gross = state.tangential.gross_slip
        load = max(force / cap.force_n, abs(wrench.tau_z) / cap.torque_nm)
        frames.append(
            Frame(
                incipient=gross or state.slip_fraction >= INCIPIENT_SLIP_FRACTION,
                gross=gross,
                loaded=load > LOADED_FRACTION,
                flag_incipient=estimate.slip_suspected,
                flag_gross=estimate.slip_gross,
                rezero=estimate.rezero_recommended,
            )
        )
        if gross:
            # The object slides the way the load pushes it: against the gel's force on it.
            if force > 0:
                offset -= np.array([wrench.fx, wrench.fy]) / force * SLIDE_M_PER_FRAME
            angle -= float(np.sign(wrench.tau_z)) * TURN_RAD_PER_FRAME
    return frames


def _precision_recall(frames: list[Frame], truth: str, flag: str) -> dict[str, float | int]:
    tp = sum(getattr(f, truth) and getattr(f, flag) for f in frames)
    fp = sum(getattr(f, flag) and not getattr(f, truth) for f in frames)
    fn = sum(getattr(f, truth) and not getattr(f, flag) for f in frames)
    return {
        "tp": tp,
        "fp": fp,
        "fn": fn,
        "precision": tp / (tp + fp) if tp + fp else float("nan"),
        "recall": tp / (tp + fn) if tp + fn else float("nan"),
    }


def _delay(frames: list[Frame], truth: str, flag: str) -> int | None:
    """Frames from the first true frame to the first flagged one; None if never flagged."""
    first_true = next(i for i, f in enumerate(frames) if getattr(f, truth))
    first_flag = next((i for i, f in enumerate(frames) if getattr(f, flag)), None)
    return None if first_flag is None else first_flag - first_true


def _summary(runs: list[tuple[Sequence, list[Frame]]]) -> dict:
    frames = [f for _, fs in runs for f in fs]
    negatives = [f for s, fs in runs if not s.positive for f in fs]
    gross_runs = [fs for _, fs in runs if any(f.gross for f in fs)]
    incipient_runs = [fs for _, fs in runs if any(f.incipient for f in fs)]
    return {
        "incipient_delays": [_delay(fs, "incipient", "flag_incipient") for fs in incipient_runs],
        "gross_delays": [_delay(fs, "gross", "flag_gross") for fs in gross_runs],
        "frames": len(frames),
        "incipient": _precision_recall(frames, "incipient", "flag_incipient"),
        "gross": _precision_recall(frames, "gross", "flag_gross"),
        "negative_false_alarm_rate": (
            sum(f.flag_incipient for f in negatives) / len(negatives) if negatives else 0.0
        ),
        "rezero_after_gross": sum(any(f.rezero for f in fs) for fs in gross_runs),
        "gross_sequences": len(gross_runs),
        "rezero_under_load_frames": sum(f.rezero and f.loaded for f in frames),
    }


def evaluate(
    method: str = "default",
    grips_n: tuple[float, ...] = (10.0, 7.0, 14.0),
    seed: int = 11,
    noise_grey: float = 1.0,
    objects: tuple[str, ...] = OBJECTS,
    quick: bool = False,
) -> dict:
    """Run every sequence for each grip force and object; returns per-group and overall
    precision/recall, delays and re-zero checks (see the module docstring). ``quick``: only
    the first positive and the first negative sequence of each object (a smoke test)."""
    config = estimator_config(method)
    gel = load_config(GelProfile, GEL_PROFILE)
    models = {shape: GelModel(gel, SHAPES[shape]) for shape in objects}
    groups, sequences_out, all_runs, tuning_runs = [], [], [], []
    for number, grip in enumerate(grips_n):
        rng = np.random.default_rng(seed + number)
        renderer = MarkerImageRenderer(rng=rng)
        for shape in objects:
            model = models[shape]
            cap = capacity(model, grip)
            runs = []
            chosen = sequences(shape, grip, cap)
            if quick:
                chosen = [chosen[0], next(s for s in chosen if not s.positive)]
            for sequence in chosen:
                frames = run_sequence(sequence, model, cap, config, renderer, rng, noise_grey)
                runs.append((sequence, frames))
                sequences_out.append(_sequence_row(grip, sequence, frames))
            groups.append({"grip_n": grip, "object": shape, "capacity": cap, **_summary(runs)})
            all_runs += runs
            tuning_runs += runs if number == 0 else []
    held_out = [run for run in all_runs if all(run is not t for t in tuning_runs)]
    return {
        "method": method,
        "seed": seed,
        "noise_grey": noise_grey,
        "groups": groups,
        "sequences": sequences_out,
        "overall": _summary(all_runs),
        "tuning": _summary(tuning_runs),
        "held_out": _summary(held_out) if held_out else None,
        "grips_n": grips_n,
        "tuned_on_grip_n": grips_n[0],
    }


def _sequence_row(grip: float, sequence: Sequence, frames: list[Frame]) -> dict:
    row = {
        "grip_n": grip,
        "object": sequence.shape,
        "name": sequence.name,
        "positive": sequence.positive,
        "frames": len(frames),
        "flagged_frames": sum(f.flag_incipient for f in frames),
    }
    if any(f.incipient for f in frames):
        row["incipient_delay"] = _delay(frames, "incipient", "flag_incipient")
    if any(f.gross for f in frames):
        row["gross_delay"] = _delay(frames, "gross", "flag_gross")
        row["rezero"] = any(f.rezero for f in frames)
    return row


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


def markdown(report: dict, seconds: float) -> str:
    lines = [
        "# Slip detection on the simulated gel",
        "",
        f"Estimator `{report['method']}`, seed {report['seed']}, camera noise "
        f"{report['noise_grey']} grey levels; {report['overall']['frames']} frames in "
        f"{seconds:.0f} s on {platform.processor() or platform.machine()}. Regenerate: "
        "`python scripts/eval_slip.py --out docs/SLIP_EVAL.md`. Thresholds were chosen on "
        f"the {report['tuned_on_grip_n']:g} N grip"
        + ("; the other grips are held out." if len(report["grips_n"]) > 1 else "."),
        "",
        "Per frame: incipient = slip fraction >= 0.2 or gross slip (flag `slip_suspected`); "
        "gross = the model's gross slip (flag `slip_gross`). Delay: median over the "
        "sequences of the first flagged minus the first true frame (frames at "
        f"{sensor_profile(SENSOR).fps_hz:g} Hz). False alarms: share of the negative "
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
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--method", default="default", help="estimator configuration")
    parser.add_argument("--grips", default="10,7,14", help="grip forces, N (first: tuning)")
    parser.add_argument("--seed", type=int, default=11)
    parser.add_argument("--noise-grey", type=float, default=1.0, help="camera noise sigma")
    parser.add_argument("--out", type=Path, help="write the markdown report here")
    parser.add_argument("--objects", default=",".join(OBJECTS), help="objects to grasp")
    parser.add_argument("--quick", action="store_true", help="two sequences per object")
    args = parser.parse_args(argv)
    grips = tuple(float(g) for g in args.grips.split(","))
    objects = tuple(args.objects.split(","))
    unknown = sorted(set(objects) - set(SHAPES))
    if unknown:
        parser.error(f"unknown object {unknown[0]!r}; expected some of {', '.join(SHAPES)}")
    began = time.perf_counter()
    report = evaluate(args.method, grips, args.seed, args.noise_grey, objects, args.quick)
    text = markdown(report, time.perf_counter() - began)
    if args.out:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text)
    sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
