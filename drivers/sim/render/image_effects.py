"""Configuration of the seeded image effects of ``drivers.sim.render.gel_renderer.GelRenderer``.

Every effect is off by default. Their randomness comes from the renderer's ``rng`` (one
independent stream per effect), so a render is a function of (rng seed, inputs, frame index).
"""

from __future__ import annotations

import math

from core.config import Config, config_dataclass, number


@config_dataclass
class ImageEffects(Config):
    """What degrades a rendered tactile image, in named units.

    Pixel noise: ``noise_grey``, standard deviation of additive Gaussian noise, grey levels;
    each frame index draws its own noise (drivers/sim/render/noise_bank.py).

    Lighting drift (drivers/sim/render/lighting.py), scaled by the ``drift`` level passed to
    ``render`` (dimensionless; 0 is the reference lighting, e.g. pass minutes since zeroing):
    ``drift_gain_per_level``, relative gain change of the B, G, R channels per unit level
    (0.02: 2 % brighter per level); ``drift_gradient_grey_per_level``, grey levels per unit
    level that a linear shading gradient adds at the image edge it points to (and removes at
    the opposite edge); ``drift_gradient_angle_rad``, its direction in the image (0: toward
    +x, the right edge; pi / 2: toward +y, the bottom edge).

    Optical blur: ``blur_sigma_px``, Gaussian sigma, px (0: sharp).

    Motion blur: ``motion_blur_samples``, number of displacement fields averaged over the
    exposure when ``render`` is given the field at the exposure's start, spaced evenly from
    that field to the end field (1: an instantaneous exposure at its end, no blur).

    Marker dropout: ``marker_dropout_fraction``, the fraction of printed markers whose ink
    has worn off (missing from the reference and every frame), rounded to whole markers.

    Occlusion (torn or dirty gel, drivers/sim/render/occlusion.py): ``occlusion_count`` elliptic
    blobs with semi-major axis ``occlusion_size_px`` px (semi-minor 50-100 % of it) where
    the image shows a static region that does not move with the gel (optical flow there is
    zero), of mean reflectance ``occlusion_reflectance`` (the bare gel is 1: below 1 dark,
    above 1 bright) with its own speckle of relative amplitude ``occlusion_texture``.
    """

    noise_grey: float = number(0.0, 50.0, default=0.0)
    drift_gain_per_level: tuple[float, float, float] = number(-1.0, 1.0, default=(0.0, 0.0, 0.0))
    drift_gradient_grey_per_level: float = number(-255.0, 255.0, default=0.0)
    drift_gradient_angle_rad: float = number(-2 * math.pi, 2 * math.pi, default=0.0)
    blur_sigma_px: float = number(0.0, 20.0, default=0.0)
    motion_blur_samples: int = number(1, 32, default=1)
    marker_dropout_fraction: float = number(0.0, 1.0, default=0.0)
    occlusion_count: int = number(0, 50, default=0)
    occlusion_size_px: float = number(1.0, 1000.0, default=25.0)
    occlusion_reflectance: float = number(0.0, 1.5, default=0.35)
    occlusion_texture: float = number(0.0, 0.5, default=0.1)
