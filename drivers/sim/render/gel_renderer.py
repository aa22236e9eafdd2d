"""Fast seeded marker-gel images for the simulated tactile camera (about 1-2 ms per 320 x 240
frame on one core; ``python -m evaluation bench_render`` measures it).

The image is the gel of the chosen appearance (drivers/sim/render/appearance.py: the original
``speckle`` gel of drivers/sim/render/gel_pattern.py by default, a ``realistic`` gel fitted to
real captures, or a real capture) warped by a forward displacement
field given at any grid resolution with the image's aspect (drivers/sim/render/field_grid.py: the
field convention; field_inverse.py: the backward map; image_warp.py: the resampling), then
the image effects of ``ImageEffects`` (render/image_effects.py) in the order light takes:
static occlusion over the gel (render/occlusion.py), optical blur, LED shading with its drift
(render/lighting.py), pixel noise (render/noise_bank.py), rounding to uint8 BGR.

Sub-pixel truth: the rendered displacement is the field upsampled to every pixel
(``field_grid.GridUpsampler``; the field itself at full resolution) to within a few
thousandths of a px plus OpenCV's position quantisation to 1/64 px. ``MarkerImageRenderer``
(render/marker_images.py) inverts full-resolution fields and resamples with cubic
splines at full float precision (about 20 ms a frame), for benchmarks of sub-pixel flow accuracy.
"""

from __future__ import annotations

import cv2
import numpy as np

from drivers.sim.render.appearance import make_gel_pattern
from drivers.sim.render.field_inverse import BackwardMapper
from drivers.sim.render.image_effects import ImageEffects
from drivers.sim.render.image_warp import SplineWarper
from drivers.sim.render.lighting import drift_rate, shade
from drivers.sim.render.noise_bank import NoiseBank
from drivers.sim.render.occlusion import Occlusion
from drivers.sim.render.realistic import RealisticLook


class GelRenderer:
    """Renders (H, W, 3) BGR uint8 images of a marker gel warped by forward fields.

    The gel: ``pitch_px`` marker lattice pitch (``None``: no printed markers, texture only,
    as the DIGIT's), ``dot_radius_px`` marker radius, ``jitter_px`` random offset of each
    marker from its lattice site, ``texture_grey`` amplitude of the speckle (all px or grey
    levels). ``effects``: see ``ImageEffects`` (none by default). ``rng`` seeds the gel
    (drawn first, as ``MarkerImageRenderer`` draws it: the same seed gives the same gel) and
    then one independent stream per effect.

    ``appearance`` names the gel's look (drivers/sim/render/appearance.py): ``"speckle"``
    (the default, the original synthetic gel), ``"realistic"`` / ``"realistic_digit"`` (fitted
    to real captures; a ``RealisticLook`` works too) or ``"real:<capture>"`` (a real capture
    warped). ``dot_radius_px``, ``jitter_px`` and ``texture_grey`` shape the speckle gel only;
    a real capture brings its own markers.

    ``marker_centres_px`` (N, 2) are the (x, y) px of the markers printed and present in the
    reference; ``dropped_marker_centres_px`` those worn off by marker dropout;
    ``occlusion_alpha`` (H, W) in [0, 1] the static blobs' cover, or ``None``.
    """

    def __init__(
        self,
        width_px: int = 320,
        height_px: int = 240,
        pitch_px: float | None = 31.5,
        dot_radius_px: float = 4.5,
        jitter_px: float = 1.5,
        texture_grey: float = 12.0,
        effects: ImageEffects | None = None,
        rng: np.random.Generator | None = None,
        appearance: str | RealisticLook = "speckle",
    ) -> None:
        rng = np.random.default_rng(0) if rng is None else rng
        self.effects = effects = ImageEffects() if effects is None else effects
        self.shape_hw = shape_hw = (height_px, width_px)
        pattern = make_gel_pattern(
            appearance, shape_hw, pitch_px, dot_radius_px, jitter_px, texture_grey, rng
        )
        centres = pattern.marker_centres_px
        dropout_seed, occlusion_seed, noise_seed = np.random.SeedSequence(
            int(rng.integers(2**63))
        ).spawn(3)
        dropped = np.zeros(len(centres), bool)
        n_dropped = round(effects.marker_dropout_fraction * len(centres))
        dropped[
            np.random.default_rng(dropout_seed).choice(len(centres), n_dropped, replace=False)
        ] = True
        self.marker_centres_px = centres[~dropped]
        self.dropped_marker_centres_px = centres[dropped]
        self._gel = SplineWarper(pattern.reflectance(~dropped))
        self._occlusion = None
        if effects.occlusion_count > 0:
            self._occlusion = Occlusion(
                shape_hw,
                effects.occlusion_count,
                effects.occlusion_size_px,
                effects.occlusion_reflectance,
                effects.occlusion_texture,
                np.random.default_rng(occlusion_seed),
            )
        self._noise = None
        if effects.noise_grey > 0:
            self._noise = NoiseBank((height_px, width_px, 3), effects.noise_grey, noise_seed)
        self._shading = pattern.shading
        self._drift_rate = drift_rate(
            self._shading,
            effects.drift_gain_per_level,
            effects.drift_gradient_grey_per_level,
            effects.drift_gradient_angle_rad,
        )
        self._mapper = BackwardMapper(shape_hw)
        # (end field, start field, the gel they give): see ``_optics``
        self._last_optics: tuple[np.ndarray | None, np.ndarray | None, np.ndarray] | None = None

    @property
    def occlusion_alpha(self) -> np.ndarray | None:
        return None if self._occlusion is None else self._occlusion.alpha

    def backward_map(self, displacement_px: np.ndarray) -> np.ndarray:
        """The reference position (x, y) px that each output pixel shows, (H, W, 2) float32,
        for the forward field ``displacement_px`` (h, w, 2) px at any grid resolution with
        the image's aspect (see drivers/sim/render/field_grid.py)."""
        return self._mapper(displacement_px)

    def render(
        self,
        displacement_px: np.ndarray | None = None,
        *,
        frame_index: int = 0,
        drift: float = 0.0,
        exposure_start_px: np.ndarray | None = None,
    ) -> np.ndarray:
        """The camera image (H, W, 3) uint8 BGR after the gel moved by the forward field
        ``displacement_px`` (h, w, 2) px (``None``: the reference pose).

        ``frame_index`` (>= 0) picks the frame's pixel noise; ``drift`` is the lighting
        drift level. With ``exposure_start_px``, the field at the start of the exposure
        (``None``: the gel did not move during it), the gel is the mean of its warps by
        ``effects.motion_blur_samples`` fields evenly spaced from that field to
        ``displacement_px`` (linear in time; either may be ``None`` for zero).
        """
        gel = self._optics(displacement_px, exposure_start_px)
        shading = self._shading
        if drift != 0.0:
            shading = cv2.scaleAdd(self._drift_rate, float(drift), self._shading)
        noise = None if self._noise is None else self._noise.frame(frame_index)
        return shade(gel, shading, noise)

    def _optics(self, end_px: np.ndarray | None, start_px: np.ndarray | None) -> np.ndarray:
        """The gel's reflectance as the lens sees it, per colour channel: moved by the fields,
        occluded, blurred (float32 (H, W, 3); the caller must not change it). A function of
        the fields alone, so the last one is kept and reused when both fields equal the last
        call's (a steady press, or no contact, renders the same gel under new noise and
        lighting)."""
        last = self._last_optics
        if last is not None and _same_field(last[0], end_px) and _same_field(last[1], start_px):
            return last[2]
        gel = self._moving_gel(end_px, start_px)
        if self._occlusion is not None:
            gel = self._occlusion.apply(gel)
        if self.effects.blur_sigma_px > 0:
            gel = cv2.GaussianBlur(gel, (0, 0), self.effects.blur_sigma_px)
        if gel.ndim == 2:  # one reflectance for the three channels, as ``shade`` takes it
            gel = cv2.merge([gel, gel, gel])
        self._last_optics = (_kept(end_px), _kept(start_px), gel)
        return gel

    def _moving_gel(self, end_px: np.ndarray | None, start_px: np.ndarray | None) -> np.ndarray:
        samples = self.effects.motion_blur_samples
        if start_px is None or samples == 1:
            return self._gel.image if end_px is None else self._gel(self._mapper(end_px))
        start = np.asarray(start_px, np.float32)
        end = np.zeros_like(start) if end_px is None else np.asarray(end_px, np.float32)
        if start.shape != end.shape:
            raise ValueError(
                f"exposure_start_px: expected the end field's shape {end.shape}, got {start.shape}"
            )
        total = np.zeros_like(self._gel.image)
        for t in np.linspace(0.0, 1.0, samples, dtype=np.float32):
            total += self._gel(self._mapper(start + t * (end - start)))
        return total * np.float32(1.0 / samples)


def _kept(field: np.ndarray | None) -> np.ndarray | None:
    """A private copy of a field (the caller may change its array later)."""
    return None if field is None else np.array(field, copy=True)


def _same_field(kept: np.ndarray | None, field: np.ndarray | None) -> bool:
    """Whether ``field`` equals a field kept by ``_kept`` (None only equals None)."""
    if kept is None or field is None:
        return kept is None and field is None
    return bool(np.array_equal(kept, field))
