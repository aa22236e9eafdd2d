"""The ``realistic`` appearances: a procedural gel fitted to real captures.

``RealisticLook`` holds the numbers; ``REALISTIC`` is fitted to the two GelSight captures
with markers, ``REALISTIC_DIGIT`` to the two DIGIT captures (drivers/sim/render/real_gels/).
They were fitted by ``python -m evaluation fit_appearance`` (evaluation/appearance/fit.py):
starting from a guess, it renders the look with a few seeds, measures the rendered frames
with the same statistics as the captures (evaluation/appearance/stats.py), and scales each
parameter by the ratio of the captures' statistic to the rendered one, eight times over.
docs/SIMULATION.md tabulates the statistics real against rendered.

The gel (moves with the displacement field):
``reflectance = (1 + texture) * (1 - marker_ink * coverage)``, with the markers blurred discs
(drivers/sim/render/gel_pattern.py: ``blurred_disc_coverage``) on a square lattice at the
caller's pitch, each site moved by up to ``lattice_jitter_px`` (uniform), and the texture
Gaussian noise with the fitted RMS in each octave band (``octave_texture``). The lighting
(fixed to the camera): a smooth random coloured shading with the fitted channel means,
spreads and correlations (drivers/sim/render/lighting.py: ``random_led_shading``). Lengths
are px at an image width of 320 px and scale with the width.
"""

from __future__ import annotations

from core.config import Config, config_dataclass, number

REFERENCE_WIDTH_PX = 320
"""The image width at which a look's lengths are given, px."""


@config_dataclass
class RealisticLook(Config):
    """A procedural gel appearance (see the module docstring); px at 320 px width.

    Markers: ``marker_diameter_px`` where the ink covers half; ``marker_ink``, the fraction
    of light a marker's centre absorbs; ``marker_edge_sigma_px``, the Gaussian blur of its
    edge (10-90 % width: 2.563 sigma); ``lattice_jitter_px``, the largest offset of a marker
    from its lattice site along each axis.

    Texture: ``texture_band_rms``, the RMS relative reflectance in each octave band between
    the sigmas of drivers/sim/render/gel_analysis.py ``OCTAVE_SIGMAS_PX``, finest first.

    Lighting: ``light_mean_bgr`` and ``light_spread_bgr``, the mean and standard deviation
    over the image of each channel's shading, grey levels; ``light_correlation_bg_br_gr``,
    the correlation coefficients between channels (B-G, B-R, G-R);
    ``light_scale_px``, the correlation length of the shading.
    """

    marker_diameter_px: float = number(1.0, 100.0)
    marker_ink: float = number(0.0, 1.0)
    marker_edge_sigma_px: float = number(0.05, 20.0)
    lattice_jitter_px: float = number(0.0, 20.0)
    texture_band_rms: tuple[float, float, float, float, float] = number(0.0, 1.0)
    light_mean_bgr: tuple[float, float, float] = number(0.0, 255.0)
    light_spread_bgr: tuple[float, float, float] = number(0.0, 128.0)
    light_correlation_bg_br_gr: tuple[float, float, float] = number(-1.0, 1.0)
    light_scale_px: float = number(8.0, 1000.0)

    def __post_init__(self) -> None:
        bg, br, gr = self.light_correlation_bg_br_gr
        if 1 + 2 * bg * br * gr - bg**2 - br**2 - gr**2 <= 0:
            raise ValueError(
                "key 'light_correlation_bg_br_gr': expected the coefficients of a valid "
                f"(positive definite) correlation matrix, got {self.light_correlation_bg_br_gr!r}"
            )


REALISTIC = RealisticLook(
    marker_diameter_px=11.66,
    marker_ink=0.7158,
    marker_edge_sigma_px=0.5884,
    lattice_jitter_px=0.8,
    texture_band_rms=(0.002381, 0.01058, 0.005889, 0.0, 0.01684),
    light_mean_bgr=(208.0, 169.3, 197.1),
    light_spread_bgr=(19.89, 20.86, 29.9),
    light_correlation_bg_br_gr=(-0.7194, -0.09037, -0.5199),
    light_scale_px=100.0,
)
"""Fitted to gelsight_markers_a and _b (``python -m evaluation fit_appearance realistic``)."""

REALISTIC_DIGIT = RealisticLook(
    marker_diameter_px=11.66,
    marker_ink=0.7158,
    marker_edge_sigma_px=0.5884,
    lattice_jitter_px=0.8,
    texture_band_rms=(0.003229, 0.006448, 0.004304, 0.0, 0.01746),
    light_mean_bgr=(98.11, 105.7, 99.52),
    light_spread_bgr=(20.19, 25.32, 46.41),
    light_correlation_bg_br_gr=(-0.2279, 0.6662, -0.0158),
    light_scale_px=100.0,
)
"""Fitted to digit_background_a and _b, which have no markers (``python -m
evaluation fit_appearance realistic_digit``); its marker numbers are REALISTIC's, for a
DIGIT gel given printed markers."""
