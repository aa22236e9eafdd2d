"""Named appearances of the rendered gel: what the gel carries and how the LEDs light it.

A caller names one (``GelRenderer(..., appearance=NAME)``, ``MarkerImageRenderer`` too):

* ``"speckle"``: the original synthetic gel: tanh-edged markers of the caller's
  ``dot_radius_px`` over a fine speckle of ``texture_grey`` (drivers/sim/render/gel_pattern.py),
  under a fixed three-colour gradient (``led_shading``). Bit-identical to the renderer before
  appearances existed, and still the default.
* ``"realistic"``: a procedural gel fitted to the real GelSight captures
  (drivers/sim/render/realistic.py ``REALISTIC``): larger, soft-edged markers, a faint
  texture, smooth coloured LED shading drawn from the renderer's ``rng``;
  ``"realistic_digit"`` the same fitted to the DIGIT captures (``REALISTIC_DIGIT``). A
  ``RealisticLook`` instance may be passed instead of a name (e.g. to sweep the lighting).
* ``"real:<name>"``: a real capture from drivers/sim/render/real_gels/ (``real_gel_names()``),
  fitted to the image size, split into a static shading and a reflectance that moves with
  the gel (drivers/sim/render/real_texture.py). Its markers are the capture's own; the
  caller's pitch, radius, jitter and texture are not used.

For speckle and realistic gels the lattice is the caller's ``pitch_px`` (``None``: no
markers). Each appearance is a ``GelPattern``: the markers' centres, the static shading, and
the reflectance with a chosen subset of the markers printed (the rest worn off: marker
dropout).
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from drivers.sim.render.gel_analysis import OCTAVE_SIGMAS_PX
from drivers.sim.render.gel_pattern import (
    blurred_disc_coverage,
    marker_coverage,
    marker_lattice,
    octave_texture,
    reflectance,
    speckle,
)
from drivers.sim.render.lighting import led_shading, random_led_shading
from drivers.sim.render.real_texture import fit_to_size, load_capture, real_gel_names, split_capture
from drivers.sim.render.realistic import (
    REALISTIC,
    REALISTIC_DIGIT,
    REFERENCE_WIDTH_PX,
    RealisticLook,
)

REAL_PREFIX = "real:"
_LOOKS = {"realistic": REALISTIC, "realistic_digit": REALISTIC_DIGIT}


def appearance_names() -> tuple[str, ...]:
    """Every name ``make_gel_pattern`` takes."""
    return ("speckle", *_LOOKS, *(REAL_PREFIX + name for name in real_gel_names()))


class GelPattern(Protocol):
    """The gel of one appearance at one image size, in its reference pose.

    ``marker_centres_px`` (N, 2) (x, y) px; ``shading`` float32 (H, W, 3) BGR grey levels for
    reflectance 1, fixed to the camera."""

    marker_centres_px: np.ndarray
    shading: np.ndarray

    def reflectance(self, printed: np.ndarray) -> np.ndarray:
        """float32 (H, W) or (H, W, 3) with only the markers ``printed`` (bool (N,))."""
        ...


def make_gel_pattern(
    appearance: str | RealisticLook,
    shape_hw: tuple[int, int],
    pitch_px: float | None,
    dot_radius_px: float,
    jitter_px: float,
    texture_grey: float,
    rng: np.random.Generator,
) -> GelPattern:
    """The appearance's gel (see the module docstring); ValueError naming the known names
    for an unknown one. Draws from ``rng`` (speckle: the lattice, then the speckle)."""
    if isinstance(appearance, RealisticLook):
        return RealisticPattern(appearance, shape_hw, pitch_px, rng)
    if appearance == "speckle":
        return SpecklePattern(shape_hw, pitch_px, dot_radius_px, jitter_px, texture_grey, rng)
    if appearance in _LOOKS:
        return RealisticPattern(_LOOKS[appearance], shape_hw, pitch_px, rng)
    if isinstance(appearance, str) and appearance.startswith(REAL_PREFIX):
        name = appearance[len(REAL_PREFIX) :]
        if name in real_gel_names():
            return RealPattern(name, shape_hw)
    raise ValueError(
        f"appearance: expected one of {', '.join(appearance_names())} or a RealisticLook, "
        f"got {appearance!r}"
    )


class SpecklePattern:
    """The ``speckle`` gel (drivers/sim/render/gel_pattern.py)."""

    def __init__(
        self,
        shape_hw: tuple[int, int],
        pitch_px: float | None,
        dot_radius_px: float,
        jitter_px: float,
        texture_grey: float,
        rng: np.random.Generator,
    ) -> None:
        self.shape_hw = shape_hw
        self.marker_centres_px = (
            np.empty((0, 2))
            if pitch_px is None
            else marker_lattice(shape_hw, pitch_px, jitter_px, rng)
        )
        self._speckle = speckle(shape_hw, texture_grey, rng)
        self._radius_px = dot_radius_px
        self.shading = led_shading(shape_hw)

    def reflectance(self, printed: np.ndarray) -> np.ndarray:
        coverage = marker_coverage(self.shape_hw, self.marker_centres_px[printed], self._radius_px)
        return reflectance(self._speckle, coverage)


class RealisticPattern:
    """A ``RealisticLook``'s gel (drivers/sim/render/realistic.py); draws the lattice, the
    texture and the lighting from ``rng`` in that order."""

    def __init__(
        self,
        look: RealisticLook,
        shape_hw: tuple[int, int],
        pitch_px: float | None,
        rng: np.random.Generator,
    ) -> None:
        self.shape_hw = shape_hw
        self.look = look
        self._scale = scale = shape_hw[1] / REFERENCE_WIDTH_PX
        self.marker_centres_px = (
            np.empty((0, 2))
            if pitch_px is None
            else marker_lattice(shape_hw, pitch_px, look.lattice_jitter_px * scale, rng)
        )
        sigmas = tuple(s * scale for s in OCTAVE_SIGMAS_PX)
        self._texture = octave_texture(shape_hw, look.texture_band_rms, sigmas, rng)
        self.shading = random_led_shading(
            shape_hw,
            look.light_mean_bgr,
            look.light_spread_bgr,
            look.light_correlation_bg_br_gr,
            look.light_scale_px * scale,
            rng,
        )

    def reflectance(self, printed: np.ndarray) -> np.ndarray:
        coverage = blurred_disc_coverage(
            self.shape_hw,
            self.marker_centres_px[printed],
            self.look.marker_diameter_px * self._scale,
            self.look.marker_edge_sigma_px * self._scale,
        )
        return (1.0 + self._texture) * (1.0 - np.float32(self.look.marker_ink) * coverage)


class RealPattern:
    """A real capture's gel (drivers/sim/render/real_texture.py); draws nothing."""

    def __init__(self, name: str, shape_hw: tuple[int, int]) -> None:
        self.name = name
        self._capture = split_capture(fit_to_size(load_capture(name), shape_hw))
        self.marker_centres_px = self._capture.markers.centres_px
        self.shading = self._capture.shading

    def reflectance(self, printed: np.ndarray) -> np.ndarray:
        return self._capture.without_markers(~np.asarray(printed, bool))
