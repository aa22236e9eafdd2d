"""The simulated camera's renderer for a sensor profile, with the evaluation's nominal image
effects (a little pixel noise, as every camera has)."""

from __future__ import annotations

import numpy as np

from drivers.sim.render.gel_renderer import GelRenderer
from drivers.sim.render.image_effects import ImageEffects
from drivers.tactile.profile import sensor_profile

NOMINAL_EFFECTS = ImageEffects(noise_grey=2.0)


def make_renderer(
    sensor: str, effects: ImageEffects = NOMINAL_EFFECTS, seed: int = 0
) -> GelRenderer:
    """A seeded renderer at the sensor's working image size, with printed markers at the
    sensor's pitch (none for a gel without markers)."""
    profile = sensor_profile(sensor)
    return GelRenderer(
        width_px=profile.width_px,
        height_px=profile.height_px,
        pitch_px=profile.marker_pitch_px,
        effects=effects,
        rng=np.random.default_rng(seed),
    )
