"""False alarms of the estimator's slip flags on slip-free sequences with realistic gel images.

The dedicated slip sequences (evaluation/experiments/slip_eval.py) hold the grip constant. On
the robot the plug is pushed on the port: the grip's normal load swings while the face tilts.
Here the gel model (drivers/sim/gel) is driven, for each object, through sequences that never
slip:

* ``tilt``: about x to 60% of the lift-off torque (at the lowest grip of any sequence), back
  through zero to -60% and home, then the same about y;
* ``tilt, push ±25%`` / ``tilt, push ±50%``: the same tilt while the normal load swings
  sinusoidally by that fraction of the grip (two periods per axis);
* ``press-release``: from a light touch (25% of the grip, the reference) the load is pressed
  to 150% of the grip, held, released to the touch and pressed again.

Each frame is rendered by ``GelRenderer`` in one appearance (``realistic``, the procedural
gel fitted to real GelSight captures, and ``real:<capture>`` textures), with camera noise, and
run through the estimator zeroed on the first frame. The result per sequence: the share of
frames flagged ``slip_suspected`` and ``slip_gross``, and the frames the model itself calls
slipping (slip fraction >= ``INCIPIENT_SLIP_FRACTION`` or gross slip; they must be none, else
the sequence is not slip-free and its frames are left out of the rates).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from controller.tactile import estimator_for_sensor
from drivers.sim.gel.model import GelModel, Wrench
from drivers.sim.render.image_effects import ImageEffects
from evaluation.common.rendering import make_renderer
from evaluation.common.sim_setup import gel_model
from evaluation.experiments.slip_eval import INCIPIENT_SLIP_FRACTION, SENSOR, capacity

APPEARANCES = ("realistic", "real:gelsight_markers_a", "real:gelsight_markers_b")
OBJECTS = ("plate", "square_peg")
GRIP_N = 10.0
TILT_FRACTION = 0.6  # of the lift-off torque at the sequence's lowest grip
NOISE_GREY = 2.0
SWINGS = (0.25, 0.5)


@dataclass(frozen=True)
class Sequence:
    name: str
    grips_n: tuple[float, ...]
    wrenches: tuple[Wrench, ...]


def _there_and_back(frames: int = 12) -> np.ndarray:
    up = np.linspace(0.0, 1.0, frames + 1)[1:]
    return np.concatenate([np.zeros(3), up, 1 - 2 * up, up - 1, np.zeros(3)])


def sequences(model: GelModel, grip_n: float = GRIP_N) -> list[Sequence]:
    """The slip-free sequences of the module docstring for one object."""
    low = capacity(model, grip_n * (1.0 - max(SWINGS)))
    profile = _there_and_back()
    n = len(profile)
    tilts = [Wrench(tau_x=TILT_FRACTION * a * low.tilt_x_nm) for a in profile]
    tilts += [Wrench(tau_y=TILT_FRACTION * a * low.tilt_y_nm) for a in profile]
    phase = 2.0 * np.pi * 2.0 * np.arange(2 * n) / n  # two periods per axis
    out = [Sequence("tilt", (grip_n,) * len(tilts), tuple(tilts))]
    for swing in SWINGS:
        grips = tuple(float(g) for g in grip_n * (1.0 + swing * np.sin(phase)))
        out.append(Sequence(f"tilt, push ±{swing:.0%}", grips, tuple(tilts)))
    touch, press = 0.25 * grip_n, 1.5 * grip_n
    ramp = list(np.linspace(touch, press, 13)[1:])
    cycle = [touch] * 3 + ramp + [press] * 6 + ramp[::-1] + [touch] * 4
    grips = tuple(float(g) for g in cycle + cycle[3:])
    out.append(Sequence("press-release", grips, (Wrench(),) * len(grips)))
    return out


def run_sequence(sequence: Sequence, model: GelModel, estimator, renderer) -> dict:
    """Flag counts of one sequence (the estimator zeroed on its first grip, unloaded)."""
    estimator.set_reference(renderer.render(model.solve(sequence.grips_n[0], Wrench()).field_px))
    suspected = gross = truth = 0
    for index, (grip, wrench) in enumerate(zip(sequence.grips_n, sequence.wrenches, strict=True)):
        state = model.solve(grip, wrench)
        estimate = estimator.push(
            renderer.render(state.field_px, frame_index=index + 1),
            index / estimator.profile.fps_hz,
        )
        suspected += estimate.slip_suspected
        gross += estimate.slip_gross
        truth += state.tangential.gross_slip or state.slip_fraction >= INCIPIENT_SLIP_FRACTION
    return {
        "frames": len(sequence.grips_n),
        "slip_suspected": suspected,
        "slip_gross": gross,
        "truth_slip": truth,
    }


def evaluate(
    method: str | None = None,
    appearances: tuple[str, ...] = APPEARANCES,
    objects: tuple[str, ...] = OBJECTS,
    seed: int = 5,
) -> dict:
    """Per-sequence rows and the totals over the slip-free frames (see the module docstring)."""
    rows = []
    for k, appearance in enumerate(appearances):
        estimator = estimator_for_sensor(SENSOR, method)
        renderer = make_renderer(SENSOR, ImageEffects(noise_grey=NOISE_GREY), seed + k, appearance)
        for shape in objects:
            model = gel_model(SENSOR, shape)
            for sequence in sequences(model):
                counts = run_sequence(sequence, model, estimator, renderer)
                rows.append(
                    {"appearance": appearance, "object": shape, "name": sequence.name, **counts}
                )
    clean = [r for r in rows if r["truth_slip"] == 0]
    frames = sum(r["frames"] for r in clean)
    return {
        "method": estimator.config_name,
        "seed": seed,
        "appearances": appearances,
        "rows": rows,
        "frames": frames,
        "suspected_rate": sum(r["slip_suspected"] for r in clean) / frames if frames else 0.0,
        "gross_rate": sum(r["slip_gross"] for r in clean) / frames if frames else 0.0,
        "worst_suspected_rate": max(
            (r["slip_suspected"] / r["frames"] for r in clean), default=0.0
        ),
    }


def false_alarm_table(reports: list[dict]) -> list[str]:
    """Markdown: per method, the flagged share per sequence kind and in total."""
    names = list(dict.fromkeys(r["name"] for r in reports[0]["rows"]))
    lines = [
        "| method | " + " | ".join(names) + " | all: suspected / gross | worst sequence |",
        "|---|" + "---|" * (len(names) + 2),
    ]
    for report in reports:
        cells = []
        for name in names:
            rows = [r for r in report["rows"] if r["name"] == name and r["truth_slip"] == 0]
            frames = sum(r["frames"] for r in rows)
            cells.append(
                f"{sum(r['slip_suspected'] for r in rows) / frames:.1%}" if frames else "n/a"
            )
        lines.append(
            f"| {report['method']} | "
            + " | ".join(cells)
            + f" | {report['suspected_rate']:.1%} / {report['gross_rate']:.1%}"
            + f" | {report['worst_suspected_rate']:.1%} |"
        )
    return lines
