"""Simulated calibration datasets: the jig scene rendered frame by frame into the dataset
format of ``controller.offline.dataset`` (the same one a recording uses)."""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import asdict
from pathlib import Path
from typing import Protocol

import numpy as np

from controller.offline.dataset import DatasetMeta, DatasetWriter, Segment
from drivers.sim.gel.model import GelModel
from drivers.sim.scenes.jig import (
    Experiment,
    JigConfig,
    JigGel,
    ft_samples,
    jig_program,
    tactile_times,
)


class FrameRenderer(Protocol):
    def render(self, displacement_px: np.ndarray, *, frame_index: int) -> np.ndarray:
        """The camera image (H, W, 3) BGR uint8 for a forward image field (px) on a grid
        of cells covering the image."""


MAX_FRAMES_PER_AXIS = 1_000_000  # 14.6 h of frames at 19 Hz; more is a typing mistake


def paper_experiments(
    axes: Sequence[str], amplitudes_nm: Sequence[float], frames_per_axis: int, config: JigConfig
) -> list[Experiment]:
    """Experiments that cycle through ``amplitudes_nm`` about each axis until about
    ``frames_per_axis`` tactile frames have been captured for it. Raises ValueError for a
    count outside [1, MAX_FRAMES_PER_AXIS], a repeated axis or no amplitude."""
    if (
        isinstance(frames_per_axis, bool)
        or not isinstance(frames_per_axis, int)
        or not 1 <= frames_per_axis <= MAX_FRAMES_PER_AXIS
    ):
        raise ValueError(
            f"frames per axis: expected a whole number in [1, {MAX_FRAMES_PER_AXIS}], "
            f"got {frames_per_axis!r}"
        )
    if len(set(axes)) != len(axes) or not amplitudes_nm:
        raise ValueError(f"expected distinct axes and at least one amplitude, got {axes!r}")
    mean_pulse_s = (
        config.ramp_min_s
        + config.ramp_max_s
        + (config.hold_min_s + config.hold_max_s) / 2
        + (config.rest_min_s + config.rest_max_s) / 2
    )
    seconds = frames_per_axis / config.tactile_rate_hz
    pulses = max(1, round(seconds / mean_pulse_s / len(amplitudes_nm)))
    return [Experiment(axis, amplitude, pulses) for axis in axes for amplitude in amplitudes_nm]


def write_jig_dataset(
    folder: Path | str,
    sensor: str,
    model: GelModel,
    renderer: FrameRenderer,
    experiments: Sequence[Experiment],
    config: JigConfig,
    seed: int,
    extras: dict | None = None,
    replace: bool = False,
) -> dict[str, float]:
    """Simulate the jig running ``experiments`` and write the dataset to ``folder`` (all or
    nothing, ``DatasetWriter``; ``replace``: an existing dataset there is replaced once the
    new one is complete). Returns timing: frames, seconds for the physics and for the
    rendering."""
    rng = np.random.default_rng(seed)
    program = jig_program(experiments, config, rng)
    frame_times = tactile_times(program, config, rng)
    ft_t, ft_wrench = ft_samples(program, config, rng)
    meta = DatasetMeta(
        sensor=sensor,
        source="simulation",
        gel_load_factor=config.gel_load_factor,
        reference=program.reference,
        open=(0.0, config.open_s),
        segments=tuple(
            Segment(s.axis, s.amplitude_nm, s.t_start_s, s.t_end_s) for s in program.segments
        ),
        extras={
            "seed": seed,
            "object": model.shape.kind,
            "gel_profile": asdict(model.profile),
            "jig": asdict(config),
            **(extras or {}),
        },
    )
    gel = JigGel(model, program, config)
    physics_s = render_s = 0.0
    with DatasetWriter(folder, meta, config.tactile_rate_hz, replace=replace) as writer:
        writer.write_ft(ft_t, ft_wrench)
        for index, t_s in enumerate(frame_times):
            start = time.perf_counter()
            state = gel.state(float(t_s))
            middle = time.perf_counter()
            image = renderer.render(state.field_px, frame_index=index)
            physics_s += middle - start
            render_s += time.perf_counter() - middle
            writer.add_frame(float(t_s), image)
            carried = state.carried
            writer.add_truth(
                {
                    "t_s": t_s,
                    "fx_n": carried.fx,
                    "fy_n": carried.fy,
                    "fz_n": carried.fz,
                    "tau_x_nm": carried.tau_x,
                    "tau_y_nm": carried.tau_y,
                    "tau_z_nm": carried.tau_z,
                    "slip_fraction": state.slip_fraction,
                    "gross_slip": float(state.tangential.gross_slip),
                    "lifted_off": float(state.lifted_off),
                }
            )
    return {"frames": float(frame_times.size), "physics_s": physics_s, "render_s": render_s}
