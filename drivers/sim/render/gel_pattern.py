"""The printed gel of a visuotactile sensor in its reference pose, as a reflectance image.

Coordinates are px in the image: x along the columns (right), y along the rows (down), pixel
centres at integers. The gel carries dark printed markers (discs with sub-pixel centres on a
jittered square lattice) over a texture; its reflectance is about 1 on the bare gel. The LED
lighting (drivers/sim/render/lighting.py) turns reflectance into grey levels.

Two looks are built from these parts (drivers/sim/render/appearance.py): ``speckle``, the
original synthetic gel (markers with a tanh edge about 0.25 reflectance inside, over a fine
speckle: ``speckle``, ``marker_coverage``, ``reflectance``), and ``realistic``, fitted to real
captures (markers with a Gaussian-blurred edge: ``blurred_disc_coverage``; a faint texture
with a fitted octave spectrum: ``octave_texture``).
"""

from __future__ import annotations

import cv2
import numpy as np
from scipy.spatial import cKDTree
from scipy.special import ndtr

MARKER_INK = 0.75
"""Fraction of the gel's reflectance a fully inked marker absorbs."""

_EDGE_PX = 0.7  # softness of a marker's edge (tanh width), px


def marker_lattice(
    shape_hw: tuple[int, int], pitch_px: float, jitter_px: float, rng: np.random.Generator
) -> np.ndarray:
    """Marker centres (N, 2) px (x, y): a square lattice of ``pitch_px`` starting half a pitch
    from the top-left corner, each site moved by a uniform random offset of up to
    ``jitter_px`` along each axis."""
    height, width = shape_hw
    cx, cy = np.meshgrid(
        np.arange(pitch_px / 2, width, pitch_px), np.arange(pitch_px / 2, height, pitch_px)
    )
    centres = np.stack([cx.ravel(), cy.ravel()], axis=1)
    return centres + rng.uniform(-jitter_px, jitter_px, centres.shape)


def speckle(shape_hw: tuple[int, int], texture_grey: float, rng: np.random.Generator) -> np.ndarray:
    """Relative reflectance variation of the gel's speckle, float32 (H, W): white noise blurred
    by a 1.5 px Gaussian, scaled so it shows about ``texture_grey`` grey levels (std) under
    the lighting's typical level."""
    noise = cv2.GaussianBlur(rng.standard_normal(shape_hw).astype(np.float32), (0, 0), 1.5)
    noise *= texture_grey / (255.0 * 0.6 * max(float(noise.std()), 1e-6))
    return noise


def marker_coverage(
    shape_hw: tuple[int, int], centres_px: np.ndarray, radius_px: float
) -> np.ndarray:
    """Ink coverage float32 (H, W) in [0, 1]: 1 inside a marker disc of ``radius_px`` around
    each centre (x, y) px, 0 outside, with a soft anti-aliased edge about one pixel wide."""
    height, width = shape_hw
    ys, xs = np.mgrid[0:height, 0:width].astype(np.float32)
    coverage = np.zeros((height, width), np.float32)
    reach = radius_px + 3
    for x, y in centres_px:
        x0, x1 = int(max(0, x - reach)), int(min(width, x + reach + 1))
        y0, y1 = int(max(0, y - reach)), int(min(height, y + reach + 1))
        r = np.hypot(xs[y0:y1, x0:x1] - x, ys[y0:y1, x0:x1] - y)
        np.maximum(
            coverage[y0:y1, x0:x1],
            0.5 * (1.0 - np.tanh((r - radius_px) / _EDGE_PX)),
            out=coverage[y0:y1, x0:x1],
        )
    return coverage


def reflectance(speckle_rel: np.ndarray, coverage: np.ndarray) -> np.ndarray:
    """The gel's reflectance float32 (H, W): speckled bare gel darkened by the markers' ink."""
    return (1.0 + speckle_rel) * (1.0 - MARKER_INK * coverage)


def blurred_disc_coverage(
    shape_hw: tuple[int, int], centres_px: np.ndarray, diameter_px: float, edge_sigma_px: float
) -> np.ndarray:
    """Ink coverage float32 (H, W) in [0, 1] of discs of ``diameter_px`` around each centre
    (x, y) px, blurred by a Gaussian of ``edge_sigma_px``: ``Phi((R - r) / sigma)`` with r the
    distance to the nearest centre (Phi: the standard normal CDF; its 10-90 % edge width is
    2.563 sigma). Zero everywhere without centres."""
    if len(centres_px) == 0:
        return np.zeros(shape_hw, np.float32)
    height, width = shape_hw
    ys, xs = np.mgrid[0:height, 0:width].astype(np.float32)
    distance, _ = cKDTree(centres_px).query(np.stack([xs.ravel(), ys.ravel()], axis=1))
    coverage = ndtr((diameter_px / 2 - distance) / edge_sigma_px)
    return coverage.reshape(shape_hw).astype(np.float32)


def octave_texture(
    shape_hw: tuple[int, int],
    band_rms: tuple[float, ...],
    band_sigmas_px: tuple[float, ...],
    rng: np.random.Generator,
) -> np.ndarray:
    """A Gaussian random texture float32 (H, W) of zero mean whose octave band k (white noise
    filtered by the difference of Gaussians of sigmas ``band_sigmas_px[k]`` and
    ``band_sigmas_px[k + 1]``, px; 0 is no blur) has RMS ``band_rms[k]``: the sum of one such
    band of independent white noise per entry, each scaled to that RMS."""
    if len(band_sigmas_px) != len(band_rms) + 1:
        raise ValueError(
            f"band_sigmas_px: expected {len(band_rms) + 1} sigmas for {len(band_rms)} bands, "
            f"got {len(band_sigmas_px)}"
        )
    texture = np.zeros(shape_hw, np.float32)
    for rms, fine, coarse in zip(band_rms, band_sigmas_px[:-1], band_sigmas_px[1:], strict=True):
        white = rng.standard_normal(shape_hw).astype(np.float32)
        band = _blur(white, fine) - _blur(white, coarse)
        texture += band * np.float32(rms / max(float(band.std()), 1e-9))
    return texture


def _blur(image: np.ndarray, sigma_px: float) -> np.ndarray:
    return image if sigma_px == 0 else cv2.GaussianBlur(image, (0, 0), sigma_px)
