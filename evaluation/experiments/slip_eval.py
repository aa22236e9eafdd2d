"""Precision, recall and delay of the estimator's slip flags on the simulated gel.

Each sequence drives the gel model (drivers/sim/gel) with a grip force and a wrench per
frame, renders the marker-gel image with the simulated camera (evaluation.common.rendering, seeded
pixel noise), and runs the estimator on it, zeroed on the grasp's first frame, exactly as on
hardware. The flags are scored per frame against the model's truth:

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

The thresholds in configs/estimators/*.yaml were chosen on the 10 N grip; the 7 N and 14 N
grips (other friction capacities, other seeds) are held out.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from controller.tactile import EstimatorConfig, TactileEstimator, estimator_for_sensor
from core.sensor_profile import sensor_profile
from drivers.sim.gel.model import GelModel, GelState, Wrench
from drivers.sim.render.gel_renderer import GelRenderer
from drivers.sim.render.image_effects import ImageEffects
from evaluation.common.rendering import Appearance, make_renderer
from evaluation.common.sim_setup import gel_model

SENSOR = "gelsight_mini"
OBJECTS = ("plate", "square_peg")
GRIPS_N = (10.0, 7.0, 14.0)  # the first is the tuning grip
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


def run_sequence(
    sequence: Sequence,
    model: GelModel,
    cap: Capacity,
    estimator: TactileEstimator,
    renderer: GelRenderer,
) -> list[Frame]:
    """Drive the model through the sequence (the object slides while in gross slip), render
    and estimate each frame (the estimator zeroed on the grasp's first frame)."""
    rest = model.solve(sequence.grips_n[0], Wrench())
    estimator.set_reference(renderer.render(rest.field_px, frame_index=0))
    offset, angle, frames = np.zeros(2), 0.0, []
    for index, (grip, wrench) in enumerate(zip(sequence.grips_n, sequence.wrenches, strict=True)):
        state = model.solve(grip, wrench, offset_m=(offset[0], offset[1]), angle_rad=angle)
        image = renderer.render(state.field_px, frame_index=index + 1)
        estimate = estimator.push(image, index / estimator.profile.fps_hz)
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


def confusion(truth: np.ndarray, flagged: np.ndarray) -> tuple[int, int, int]:
    """(true positives, false positives, false negatives) of per-frame boolean flags."""
    truth, flagged = np.asarray(truth, bool), np.asarray(flagged, bool)
    return (
        int(np.sum(truth & flagged)),
        int(np.sum(flagged & ~truth)),
        int(np.sum(truth & ~flagged)),
    )


def precision_recall(tp: int, fp: int, fn: int) -> dict[str, float | int]:
    """The counts with precision and recall (NaN when undefined)."""
    return {
        "tp": tp,
        "fp": fp,
        "fn": fn,
        "precision": tp / (tp + fp) if tp + fp else float("nan"),
        "recall": tp / (tp + fn) if tp + fn else float("nan"),
    }


def _precision_recall(frames: list[Frame], truth: str, flag: str) -> dict[str, float | int]:
    truths = [getattr(f, truth) for f in frames]
    return precision_recall(*confusion(truths, [getattr(f, flag) for f in frames]))


def _delay(frames: list[Frame], truth: str, flag: str) -> int | None:
    """Frames from the first true frame to the first flagged one; None if never flagged."""
    first_true = next(i for i, f in enumerate(frames) if getattr(f, truth))
    first_flag = next((i for i, f in enumerate(frames) if getattr(f, flag)), None)
    return None if first_flag is None else first_flag - first_true


def _summary(runs) -> dict:
    """Scores over ``runs``, (sequence, frames) pairs."""
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


@dataclass(frozen=True)
class GripRuns:
    """Every sequence run at one grip force with the estimator ``method``: per object, its
    capacity and its runs."""

    grip_n: float
    method: str
    groups: tuple[tuple[str, Capacity, tuple[tuple[Sequence, tuple[Frame, ...]], ...]], ...]


def run_grip(
    grip_n: float,
    seed: int,
    method: str | tuple[str, EstimatorConfig] | None = None,
    noise_grey: float = 1.0,
    objects: tuple[str, ...] = OBJECTS,
    quick: bool = False,
    appearance: Appearance = None,
) -> GripRuns:
    """Run every sequence of every object at one grip force (one worker's job), rendered
    with ``appearance`` (None: the sensor's nominal, realistic one). ``method``: a name or
    YAML path (None: the sensor's own), or a (label, configuration) pair. ``quick``: only
    the first positive and the first negative sequence of each object (a smoke test)."""
    if isinstance(method, tuple):
        label, config = method
        estimator = TactileEstimator(config, sensor_profile(SENSOR), config_name=label)
    else:
        estimator = estimator_for_sensor(SENSOR, method)
    renderer = make_renderer(SENSOR, ImageEffects(noise_grey=noise_grey), seed, appearance)
    groups = []
    for shape in objects:
        model = gel_model(SENSOR, shape)
        cap = capacity(model, grip_n)
        chosen = sequences(shape, grip_n, cap)
        if quick:
            chosen = [chosen[0], next(s for s in chosen if not s.positive)]
        runs = tuple(
            (sequence, tuple(run_sequence(sequence, model, cap, estimator, renderer)))
            for sequence in chosen
        )
        groups.append((shape, cap, runs))
    return GripRuns(grip_n, estimator.config_name, tuple(groups))


def report(grip_runs: list[GripRuns], seed: int, noise_grey: float) -> dict:
    """Per-group and overall precision/recall, delays and re-zero checks; the first grip's
    runs are the tuning set, the others held out."""
    groups, sequences_out, tuning, held_out = [], [], [], []
    for number, grip in enumerate(grip_runs):
        for shape, cap, runs in grip.groups:
            groups.append(
                {"grip_n": grip.grip_n, "object": shape, "capacity": cap, **_summary(runs)}
            )
            sequences_out += [_sequence_row(grip.grip_n, s, frames) for s, frames in runs]
            (tuning if number == 0 else held_out).extend(runs)
    return {
        "method": grip_runs[0].method,
        "seed": seed,
        "noise_grey": noise_grey,
        "groups": groups,
        "sequences": sequences_out,
        "overall": _summary(tuning + held_out),
        "tuning": _summary(tuning),
        "held_out": _summary(held_out) if held_out else None,
        "grips_n": tuple(g.grip_n for g in grip_runs),
        "tuned_on_grip_n": grip_runs[0].grip_n,
    }


def evaluate(
    method: str | None = None,
    grips_n: tuple[float, ...] = GRIPS_N,
    seed: int = 11,
    noise_grey: float = 1.0,
    objects: tuple[str, ...] = OBJECTS,
    quick: bool = False,
    appearance: Appearance = None,
) -> dict:
    """``report`` over ``run_grip`` for each grip force in turn (grip k seeded seed + k)."""
    runs = [
        run_grip(grip, seed + k, method, noise_grey, objects, quick, appearance)
        for k, grip in enumerate(grips_n)
    ]
    return report(runs, seed, noise_grey)


def worst_recall(summary: dict) -> float:
    """The lower of the incipient and gross recalls of a ``_summary`` (NaN counts as 0)."""
    recalls = [summary[kind]["recall"] for kind in ("incipient", "gross")]
    return float(min(0.0 if np.isnan(r) else r for r in recalls))


def _sequence_row(grip: float, sequence: Sequence, frames) -> dict:
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
