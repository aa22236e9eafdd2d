"""How the tilt estimate behaves when a ball is pressed and rolled on the simulated gel.

    python -m evaluation eval_press_roll [--methods default,paper] [--seed 0] [--noise-grey 2]
        [--sensor gelsight_mini]

The scene (drivers/sim/scenes/press_roll.py) presses a ball into the gel with a rising
force, rolls it back and forth along x and y, then presses it harder while it stays rolled.
Each frame is rendered by the simulated camera (evaluation.common.rendering; the renderer is a
parameter of ``run``, so another appearance drops in) and estimated, zeroed on the first
(contact-free) frame, as on hardware.

Per estimator configuration, over the frames where the ball touches the gel (the model's
truth):

* ``degenerate``: the share of frames the estimator flags ``degenerate``;
* ``zero tilt``: the share whose tilt torques are both exactly 0.0;
* ``R^2 tau_x``, ``R^2 tau_y``: a linear fit of the raw tilt torque to the model's carried
  torque about S's origin, on the even contact frames, scored on the odd ones, and the sign
  of the fitted slope (``+``: the estimate has the torque's sign);
* ``largest step``: the largest change of the tilt estimate between consecutive frames of the
  ``press_rolled`` phase (the press changes, the roll stays), relative to the range of the
  estimate over all contact frames: a jump shows here.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass

import numpy as np

from controller.tactile import estimator_for_sensor
from core.config import ConfigError
from core.sensor_profile import sensor_profile
from core.subcommands import job_prog
from drivers.sim.render.gel_renderer import GelRenderer
from drivers.sim.render.image_effects import ImageEffects
from drivers.sim.scenes.press_roll import (
    BallGelModel,
    PressRollConfig,
    press_roll_program,
    press_roll_states,
)
from evaluation.common.rendering import make_renderer
from evaluation.common.sim_setup import gel_profile


@dataclass(frozen=True)
class PressRollScore:
    """The measurements of the module docstring for one estimator configuration."""

    method: str
    contact_frames: int
    degenerate: float
    zero_tilt: float
    r2_tau_x: float
    r2_tau_y: float
    slope_sign: tuple[int, int]
    largest_step: float


def _held_out_fit(estimate: np.ndarray, truth: np.ndarray) -> tuple[float, int]:
    """R^2 on the odd samples of a least-squares line fitted on the even ones, and the sign
    of its slope."""
    fit_x, fit_y = truth[0::2], estimate[0::2]
    slope, offset = np.polyfit(fit_x, fit_y, 1)
    test_x, test_y = truth[1::2], estimate[1::2]
    residual = test_y - (slope * test_x + offset)
    spread = test_y - test_y.mean()
    r2 = 1.0 - float(residual @ residual) / max(float(spread @ spread), 1e-300)
    return r2, int(np.sign(slope))


def run(
    sensor: str, methods: list[str], renderer: GelRenderer, scene: PressRollConfig
) -> list[PressRollScore]:
    """Render the scene once and score each estimator configuration on it."""
    profile = sensor_profile(sensor)
    estimators = [estimator_for_sensor(profile, method) for method in methods]  # fail early
    model = BallGelModel(gel_profile(sensor), scene.ball_radius_m)
    program = press_roll_program(scene)
    states = press_roll_states(model, program)
    images = [renderer.render(s.field_px, frame_index=i) for i, s in enumerate(states)]
    touching = np.array([bool(s.in_contact.any()) for s in states])
    truth = np.array([[s.carried.tau_x, s.carried.tau_y] for s in states])[touching]
    pressing = np.array([step.phase == "press_rolled" for step in program])[touching]
    scores = []
    for name, estimator in zip(methods, estimators, strict=True):
        estimator.set_reference(images[0])
        estimates = [
            estimator.push(image, step.t_s) for image, step in zip(images, program, strict=True)
        ]
        contact = [e for e, touch in zip(estimates, touching, strict=True) if touch]
        tilt = np.array([[e.tau_x, e.tau_y] for e in contact])
        steps = np.abs(np.diff(tilt[pressing], axis=0)).max(axis=0)
        span = np.ptp(tilt, axis=0)
        (r2_x, sign_x), (r2_y, sign_y) = (
            _held_out_fit(tilt[:, axis], truth[:, axis]) for axis in (0, 1)
        )
        scores.append(
            PressRollScore(
                method=name,
                contact_frames=len(contact),
                degenerate=float(np.mean([e.degenerate for e in contact])),
                zero_tilt=float(np.mean([e.tau_x == 0.0 and e.tau_y == 0.0 for e in contact])),
                r2_tau_x=r2_x,
                r2_tau_y=r2_y,
                slope_sign=(sign_x, sign_y),
                largest_step=float((steps / np.maximum(span, 1e-300)).max()),
            )
        )
    return scores


def table(scores: list[PressRollScore]) -> str:
    """A markdown table of ``scores``."""
    lines = [
        "| estimator | contact frames | degenerate | zero tilt | R^2 tau_x | R^2 tau_y "
        "| slope signs | largest step |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for s in scores:
        signs = " / ".join("+" if sign > 0 else "-" for sign in s.slope_sign)
        lines.append(
            f"| `{s.method}` | {s.contact_frames} | {s.degenerate:.1%} | {s.zero_tilt:.1%} "
            f"| {s.r2_tau_x:.3f} | {s.r2_tau_y:.3f} | {signs} | {s.largest_step:.2f} |"
        )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog=job_prog("eval_press_roll"), description=__doc__.splitlines()[0]
    )
    parser.add_argument("--methods", default="default,paper", help="estimator configurations")
    parser.add_argument("--sensor", default="gelsight_mini")
    parser.add_argument("--seed", type=int, default=0, help="seed of the rendered gel")
    parser.add_argument("--noise-grey", type=float, default=2.0, help="camera noise sigma")
    args = parser.parse_args(argv)
    try:
        renderer = make_renderer(args.sensor, ImageEffects(noise_grey=args.noise_grey), args.seed)
        scores = run(args.sensor, args.methods.split(","), renderer, PressRollConfig())
    except (ConfigError, ValueError) as error:
        parser.exit(2, f"eval_press_roll: error: {error}\n")
    sys.stdout.write(
        f"Press and roll on the simulated {args.sensor} (seed {args.seed}, noise "
        f"{args.noise_grey:g} grey levels)\n\n{table(scores)}\n"
    )
    return 0
