"""The simulated camera's renderer for a sensor profile, with the evaluation's nominal image
effects (a little pixel noise, as every camera has) and the nominal appearance: the
procedural gel fitted to that sensor's real captures (drivers/sim/render/realistic.py)."""

from __future__ import annotations

import numpy as np

from core.sensor_profile import sensor_profile
from drivers.sim.render.gel_renderer import GelRenderer
from drivers.sim.render.image_effects import ImageEffects
from drivers.sim.render.realistic import RealisticLook

NOMINAL_EFFECTS = ImageEffects(noise_grey=2.0)
NOMINAL_APPEARANCE = {"gelsight_mini": "realistic", "digit": "realistic_digit"}
"""Sensor -> the appearance the evaluation renders it with unless told otherwise."""

Appearance = str | RealisticLook | None
"""A name of drivers/sim/render/appearance.py, a ``RealisticLook``, or None: the sensor's
nominal one (``NOMINAL_APPEARANCE``)."""


def nominal_appearance(sensor: str) -> str:
    """The sensor's nominal appearance; ValueError naming the known sensors otherwise."""
    if sensor not in NOMINAL_APPEARANCE:
        raise ValueError(f"sensor: expected one of {', '.join(NOMINAL_APPEARANCE)}, got {sensor!r}")
    return NOMINAL_APPEARANCE[sensor]


def make_renderer(
    sensor: str,
    effects: ImageEffects = NOMINAL_EFFECTS,
    seed: int = 0,
    appearance: Appearance = None,
) -> GelRenderer:
    """A seeded renderer at the sensor's working image size, with printed markers at the
    sensor's pitch (none for a gel without markers), drawing ``appearance`` (None: the
    sensor's nominal one)."""
    profile = sensor_profile(sensor)
    return GelRenderer(
        width_px=profile.width_px,
        height_px=profile.height_px,
        pitch_px=profile.marker_pitch_px,
        effects=effects,
        rng=np.random.default_rng(seed),
        appearance=nominal_appearance(sensor) if appearance is None else appearance,
    )
