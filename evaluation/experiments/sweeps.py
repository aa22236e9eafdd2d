"""Stability where methods fail: each condition swept over levels, the error of every method
against the simulator's true wrench at each level, and each method's breakdown point.

A level runs a short sequence in memory (no dataset): after the grasp and the zeroing
frames, two alternating torque pulses about x, then y, then z (``SWEEP_AMPLITUDE_NM``
applied, the live gel carrying half), with the condition applied. The estimates are
calibrated with the constants fitted on the nominal dataset of the same sensor and object
(``calibration_runs``), and compared with the torques the gel really carried.

Images: each sensor's nominal appearance (evaluation.common.rendering: the procedural gel fitted to
its real captures) unless a condition changes it; the ``appearance`` conditions run the old
speckled renderer, each real capture warped by the gel model's field, and shifted lighting
colours, all calibrated with the nominal (realistic) constants.

Methods: the dipole (tau_x, tau_y), the NHHD in-plane torque (tau_z; also taken about the
rotational potential's extremum, as Zhang et al., with the same calibration constant) and
the FingerVision baseline (fv_tau_x, fv_tau_y, fv_tau_z). Per level and method: RMSE
(N*mm), R^2 over the sequence, and the RMSE normalised by the peak true torque on that
axis (NRMSE). A method breaks down at the first level, walking away from nominal (both ways
when the nominal is inside the sweep), where R^2 < 0.9 or the NRMSE exceeds twice its
nominal value. Each level also scores the slip flags per frame against the gel's
slip state (the definitions of ``evaluation.experiments.slip_eval``).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable
from dataclasses import dataclass, field

import cv2
import matplotlib.pyplot as plt
import numpy as np

from controller.offline.dataset_fit import estimate_frames
from controller.tactile import Calibration, TactileEstimator, estimator_for_sensor
from drivers.sim.gel.model import Wrench
from drivers.sim.render.image_effects import ImageEffects
from drivers.sim.render.real_texture import real_gel_names
from drivers.sim.render.realistic import REALISTIC
from drivers.sim.scenes.jig import Experiment, JigConfig, JigGel, jig_program, tactile_times
from evaluation.common.rendering import NOMINAL_EFFECTS, Appearance, make_renderer
from evaluation.common.sim_setup import gel_model, jig_config
from evaluation.experiments.slip_eval import INCIPIENT_SLIP_FRACTION, confusion

SWEEP_AMPLITUDE_NM = 0.04
ROTATION_CENTRE = "NHHD tau_z about its rotation centre"
METHOD_AXES = {  # label -> (estimate field, truth column of (fx, fy, fz, tx, ty, tz))
    "dipole tau_x": ("tau_x", 3),
    "dipole tau_y": ("tau_y", 4),
    "NHHD tau_z": ("tau_z", 5),
    ROTATION_CENTRE: ("tau_z", 5),
    "baseline tau_x": ("fv_tau_x", 3),
    "baseline tau_y": ("fv_tau_y", 4),
    "baseline tau_z": ("fv_tau_z", 5),
}
# Methods that need their own estimator pass: the default with one setting changed.
METHOD_CONFIG = {ROTATION_CENTRE: {"tau_z_about": "rotation_centre"}}


@dataclass(frozen=True)
class Setting:
    """Everything a level can change; the defaults are the nominal case."""

    sensor: str = "gelsight_mini"
    shape: str = "plate"
    amplitude_nm: float = SWEEP_AMPLITUDE_NM
    grip_force_n: float | None = None  # None: the jig's
    coupling: float = 0.0  # tau_y += k tau_x and tau_x += k tau_y
    shear_n: float = 0.0  # applied fx once the experiments start
    twist_nm: float = 0.0  # applied tau_z once the experiments start
    zero_on: str = "reference"
    effects: ImageEffects = NOMINAL_EFFECTS
    drift: float = 0.0  # lighting drift level reached at the end of the sequence
    ramp_s: float = 0.6
    exposure_fraction: float = 0.0  # motion blur: exposure as a share of the frame period
    grip_swing: float = 0.0  # pushing: grip *= 1 + grip_swing * sin(2 pi f t) once started
    appearance: Appearance = None  # None: the sensor's nominal (evaluation.common.rendering)


@dataclass(frozen=True)
class Condition:
    name: str
    unit: str
    levels: tuple[float, ...]
    nominal: float
    setting: Callable[[float], Setting]
    labels: tuple[str, ...] = field(default=())

    def level_label(self, i: int) -> str:
        return self.labels[i] if self.labels else f"{self.levels[i]:g}"


def _fraction_of_friction(fraction: float) -> Setting:
    """Applied fx such that the live gel's share is ``fraction`` of mu * grip."""
    jig = jig_config()
    capacity = 1.0 * jig.grip_force_n  # friction 1.0 in both gel profiles
    return Setting(shear_n=fraction * capacity / abs(jig.gel_load_factor))


PUSH_FREQUENCY_HZ = 0.4
"""How fast the grip swings in the pushing condition (about one swing per two pulses)."""
TILT_PX_SENSOR, TILT_PX_SHAPE = "gelsight_mini", "plate"
TILT_PX_LEVELS = (0.2, 0.4, 1.0, 2.0, 3.0)


def peak_tilt_px(applied_nm: float, sensor: str = TILT_PX_SENSOR, shape: str = TILT_PX_SHAPE):
    """The tilt motion a pulse of ``applied_nm`` (N*m, applied by the hand) makes: the
    largest displacement (px, 320x240 image) anywhere on the gel model's field grid between
    the grasped rest state (jig grip, no torque) and the peak of the pulse, the live gel
    carrying ``gel_load_factor`` of it; the larger over a pulse about x and one about y."""
    jig = jig_config()
    model = gel_model(sensor, shape)
    rest = model.solve(jig.grip_force_n, Wrench()).field_px
    carried = abs(jig.gel_load_factor) * applied_nm
    peaks = []
    for axis in ("tau_x", "tau_y"):
        moved = model.solve(jig.grip_force_n, Wrench(**{axis: carried})).field_px - rest
        peaks.append(float(np.hypot(moved[..., 0], moved[..., 1]).max()))
    return max(peaks)


@functools.cache
def tilt_amplitude_nm(peak_px: float) -> float:
    """The applied pulse amplitude (N*m) whose ``peak_tilt_px`` is ``peak_px`` (bisection;
    the relation bends above about 2 px as the face starts to lift off)."""
    low, high = 0.0, 0.4
    for _ in range(30):
        middle = 0.5 * (low + high)
        low, high = (middle, high) if peak_tilt_px(middle) < peak_px else (low, middle)
    return 0.5 * (low + high)


TEXTURES = ("speckle", *(f"real:{name}" for name in real_gel_names()))
TEXTURE_LABELS = (
    "realistic (fitted, nominal)",
    "speckle (old renderer)",
    *(f"real: {name}" for name in real_gel_names()),
)
LIGHTINGS = (
    ("fitted (nominal)", REALISTIC),
    (
        "warm (red up, blue down)",
        dataclasses.replace(REALISTIC, light_mean_bgr=(150.0, 170.0, 235.0)),
    ),
    (
        "cool (blue up, red down)",
        dataclasses.replace(REALISTIC, light_mean_bgr=(240.0, 180.0, 130.0)),
    ),
    ("green", dataclasses.replace(REALISTIC, light_mean_bgr=(150.0, 225.0, 150.0))),
    (
        "dim, 2x spread",
        dataclasses.replace(
            REALISTIC,
            light_mean_bgr=tuple(0.6 * v for v in REALISTIC.light_mean_bgr),
            light_spread_bgr=tuple(2.0 * v for v in REALISTIC.light_spread_bgr),
        ),
    ),
)


def _texture(v: float) -> Setting:
    return Setting(appearance=None if v == 0 else TEXTURES[int(v) - 1])


CONDITIONS = (
    Condition(
        "torque amplitude",
        "N*mm applied",
        (10, 20, 40, 60, 80, 120, 160),
        40,
        lambda v: Setting(amplitude_nm=v * 1e-3),
    ),
    Condition("grip force", "N", (5, 10, 15, 25, 40), 15, lambda v: Setting(grip_force_n=v)),
    Condition(
        "coupled tau_x + tau_y",
        "k (tau_y += k tau_x)",
        (0, 0.25, 0.5, 1.0),
        0,
        lambda v: Setting(coupling=v),
    ),
    Condition("shear force present", "N applied", (0, 1, 2, 4, 8), 0, lambda v: Setting(shear_n=v)),
    Condition(
        "in-plane torque present",
        "N*mm applied",
        (0, 10, 20, 40, 60),
        0,
        lambda v: Setting(twist_nm=v * 1e-3),
    ),
    Condition(
        "slip (shear / friction limit)",
        "share of mu N",
        (0, 0.5, 0.8, 0.95, 1.2),
        0,
        _fraction_of_friction,
    ),
    Condition(
        "zeroing",
        "",
        (0, 1),
        0,
        lambda v: Setting(zero_on="reference" if v == 0 else "open"),
        labels=("after grasp", "none (before grasp)"),
    ),
    Condition(
        "pixel noise",
        "grey levels",
        (0, 2, 4, 8, 16),
        2,
        lambda v: Setting(effects=ImageEffects(noise_grey=v)),
    ),
    Condition(
        "lighting drift",
        "gain change",
        (0, 0.02, 0.05, 0.1, 0.2),
        0,
        lambda v: Setting(
            effects=dataclasses.replace(
                NOMINAL_EFFECTS,
                drift_gain_per_level=(1.0, 0.8, 0.9),
                drift_gradient_grey_per_level=40.0,
            ),
            drift=v,
        ),
    ),
    Condition(
        "marker occlusion",
        "blobs of 30 px",
        (0, 1, 2, 4, 8),
        0,
        lambda v: Setting(
            effects=dataclasses.replace(
                NOMINAL_EFFECTS, occlusion_count=int(v), occlusion_size_px=30.0
            )
        ),
    ),
    Condition(
        "fast motion",
        "ramp time s",
        (0.6, 0.3, 0.15, 0.08, 0.04),
        0.6,
        lambda v: Setting(
            ramp_s=v,
            exposure_fraction=0.5,
            effects=dataclasses.replace(NOMINAL_EFFECTS, motion_blur_samples=4),
        ),
    ),
    Condition(
        "sensor",
        "",
        (0, 1),
        0,
        lambda v: Setting(sensor=("gelsight_mini", "digit")[int(v)]),
        labels=("GelSight Mini", "DIGIT"),
    ),
    Condition(
        "object shape",
        "",
        (0, 1, 2),
        0,
        lambda v: Setting(shape=("plate", "square_peg", "round_peg")[int(v)]),
        labels=("plate", "square peg", "round peg"),
    ),
    Condition(
        "tilt motion (field amplitude)",
        "peak px at 320x240",
        TILT_PX_LEVELS,
        1.0,
        lambda v: Setting(amplitude_nm=tilt_amplitude_nm(v)),
    ),
    Condition(
        "pushing (grip swing during tilt)",
        "+-% of grip",
        (0, 10, 25, 50),
        0,
        lambda v: Setting(grip_swing=v / 100),
    ),
    Condition(
        "appearance: texture",
        "",
        tuple(range(len(TEXTURE_LABELS))),
        0,
        _texture,
        labels=TEXTURE_LABELS,
    ),
    Condition(
        "appearance: lighting colour",
        "",
        tuple(range(len(LIGHTINGS))),
        0,
        lambda v: Setting(appearance=LIGHTINGS[int(v)][1]),
        labels=tuple(label for label, _ in LIGHTINGS),
    ),
)


@dataclass(frozen=True)
class LevelResult:
    condition: str
    level: float
    rmse_nmm: dict[str, float]
    r2: dict[str, float]
    nrmse: dict[str, float]
    frames: int
    slip_counts: dict[str, tuple[int, int, int]]  # "incipient"/"gross" -> (tp, fp, fn)
    slip_scored_frames: int  # the frames the slip counts cover (from the first pulse on)


def _program(setting: Setting, jig: JigConfig, rng: np.random.Generator):
    experiments = [Experiment(axis, setting.amplitude_nm, 2) for axis in ("x", "y", "z")]
    program = jig_program(experiments, jig, rng)
    wrench = program.wrench
    tx, ty = wrench[:, 3].copy(), wrench[:, 4].copy()
    wrench[:, 4] += setting.coupling * tx
    wrench[:, 3] += setting.coupling * ty
    start = program.segments[0].t_start_s
    ramp = np.clip((program.t_s - start) / 0.5, 0.0, 1.0)
    ramp = 0.5 - 0.5 * np.cos(math.pi * ramp)
    wrench[:, 0] += setting.shear_n * ramp
    wrench[:, 5] += setting.twist_nm * ramp
    swing = np.sin(2 * math.pi * PUSH_FREQUENCY_HZ * np.maximum(program.t_s - start, 0.0))
    program.grip_n[:] *= 1.0 + setting.grip_swing * ramp * swing
    return program


def run_level(
    condition_name: str,
    index: int,
    calibrations: dict[str, Calibration],
    estimator: str | None = None,
    seed: int = 7,
) -> LevelResult:
    """One level of the condition named ``condition_name`` (run in a worker process) with
    the ``estimator`` configuration (None: each sensor's own), calibrated with
    ``calibrations["SENSOR-SHAPE"]`` for the level's sensor and object."""
    condition = next(c for c in CONDITIONS if c.name == condition_name)
    cv2.setNumThreads(1)
    level = condition.levels[index]
    setting = condition.setting(level)
    base = jig_config()
    jig = dataclasses.replace(
        base,
        grip_force_n=setting.grip_force_n or base.grip_force_n,
        open_s=0.3,
        grasp_s=0.3,
        settle_s=0.6,
        ramp_min_s=setting.ramp_s,
        ramp_max_s=setting.ramp_s * 1.2,
        hold_min_s=0.2,
        hold_max_s=0.3,
        rest_min_s=0.2,
        rest_max_s=0.3,
    )
    rng = np.random.default_rng(seed)
    program = _program(setting, jig, rng)
    times = tactile_times(program, jig, rng)
    gel = JigGel(gel_model(setting.sensor, setting.shape), program, jig)
    renderer = make_renderer(setting.sensor, setting.effects, seed, setting.appearance)
    period = 1.0 / jig.tactile_rate_hz
    truth = np.empty((times.size, 6))
    slipping = np.empty(times.size)  # the gel's slip fraction
    gross = np.empty(times.size, bool)
    frames = []
    exposure_gel = JigGel(gel.model, program, jig) if setting.exposure_fraction > 0 else None
    for index_frame, t in enumerate(times):
        state = gel.state(float(t))
        truth[index_frame] = state.carried.as_array()
        slipping[index_frame] = state.slip_fraction
        gross[index_frame] = state.tangential.gross_slip
        start_field = None
        if exposure_gel is not None:
            start_field = exposure_gel.state(float(t) - setting.exposure_fraction * period).field_px
        drift = setting.drift * float(t) / program.duration_s
        image = renderer.render(
            state.field_px, frame_index=index_frame, drift=drift, exposure_start_px=start_field
        )
        frames.append((index_frame, float(t), image))
    interval = program.reference if setting.zero_on == "reference" else (0.0, jig.open_s)
    reference = [img for _, t, img in frames if interval[0] <= t < interval[1]]
    # Zeroed on the grasp, the estimator also sees the open gel (the frames before it).
    open_gel = None
    if setting.zero_on == "reference":
        open_gel = [img for _, t, img in frames if t < jig.open_s] or None
    calibration = calibrations[f"{setting.sensor}-{setting.shape}"]
    tactile = estimator_for_sensor(setting.sensor, estimator)
    series = estimate_frames(frames, reference, tactile, open_gel)
    variants = {
        label: estimate_frames(
            frames,
            reference,
            TactileEstimator(dataclasses.replace(tactile.config, **change), tactile.profile),
            open_gel,
        )
        for label, change in METHOD_CONFIG.items()
    }
    after = series.t_s >= program.segments[0].t_start_s
    rmse, r2, nrmse = {}, {}, {}
    for label, (name, column) in METHOD_AXES.items():
        fit = calibration.axes[name]
        estimate = fit.apply(variants.get(label, series).values[name][after])
        gt = truth[after, column]
        error = estimate - gt
        rmse[label] = float(np.sqrt(np.mean(error**2))) * 1e3
        total = float(((gt - gt.mean()) ** 2).sum())
        r2[label] = 1.0 - float(error @ error) / total if total > 0 else float("nan")
        nrmse[label] = rmse[label] / max(float(np.abs(gt).max()) * 1e3, 1e-9)
    incipient = gross | (slipping >= INCIPIENT_SLIP_FRACTION)
    slip_counts = {
        "incipient": confusion(incipient[after], series.slip_suspected[after]),
        "gross": confusion(gross[after], series.slip_gross[after]),
    }
    return LevelResult(
        condition.name, level, rmse, r2, nrmse, int(times.size), slip_counts, int(after.sum())
    )


def breakdown(condition: Condition, results: list[LevelResult], method: str) -> str:
    """The first level, walking away from nominal, where R^2 < 0.9 or the NRMSE doubles
    over nominal; "-" when none does. A nominal inside the sweep is walked both ways:
    "BELOW / ABOVE" (e.g. "0.2 / -": fails at 0.2, holds up to the largest level)."""
    by_level = {r.level: r for r in results}
    nominal = by_level[condition.nominal]
    if nominal.r2[method] < 0.9:
        return "fails at nominal"
    at = condition.levels.index(condition.nominal)

    def first(indices) -> str:
        for i in indices:
            result = by_level[condition.levels[i]]
            if result.r2[method] < 0.9 or result.nrmse[method] > 2.0 * nominal.nrmse[method]:
                return condition.level_label(i)
        return "-"

    above = first(range(at + 1, len(condition.levels)))
    return above if at == 0 else f"{first(range(at - 1, -1, -1))} / {above}"


def sweep_chart(results: dict[str, list[LevelResult]], path) -> None:
    """One panel per condition: NRMSE against level for every method."""
    n = len(CONDITIONS)
    cols = 4
    rows = math.ceil(n / cols)
    fig, grid = plt.subplots(rows, cols, figsize=(4.2 * cols, 3.3 * rows), squeeze=False)
    for k, condition in enumerate(CONDITIONS):
        ax = grid[k // cols][k % cols]
        levels = results[condition.name]
        xs = np.arange(len(levels))
        for label in METHOD_AXES:
            style = "-" if not label.startswith("baseline") else ":"
            ax.plot(xs, [r.nrmse[label] for r in levels], style, marker="o", ms=3, label=label)
        ax.set_xticks(
            xs, [condition.level_label(i) for i in range(len(levels))], fontsize=7, rotation=20
        )
        ax.set_yscale("log")
        ax.set_title(
            f"{condition.name} ({condition.unit})" if condition.unit else condition.name, fontsize=9
        )
        ax.set_ylabel("RMSE / peak torque", fontsize=8)
        ax.grid(True, alpha=0.3)
    for k in range(n, rows * cols):
        grid[k // cols][k % cols].axis("off")
    handles, labels = grid[0][0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower right", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)
