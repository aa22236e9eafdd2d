"""Appearance statistics of a tactile gel image, real or rendered: what the renderer's
``realistic`` appearance is fitted to and checked against (docs/SIMULATION.md).

All are measured at the image's own size (``python -m evaluation gel_stats`` first brings an
image to the sensor's working size, 320 x 240) in px and grey levels (OpenCV's BGR luma unless a
channel is named):

* **Markers** (drivers/sim/render/gel_analysis.py finds them): their count, the median
  nearest-neighbour distance (the lattice pitch), and from a least-squares fit of an edge
  model to each marker's pixels within half a pitch (at most 12 px) of its centre,
  ``I(r) = b(r) * (1 - d * Phi((R - r) / s))`` (b: the marker-free background around it,
  a 3 px normalised blur; Phi: the standard normal CDF; r: distance to the centre), the
  medians over the markers not cut by the border of: the **diameter** 2 R (where the
  darkening is half its depth), the **darkness** d (0: invisible, 1: black), and the
  **10-90 % edge width** 2 * 1.2816 * s (px over which the darkening goes from 10 to 90 %
  of its depth).
* **Shading between the markers**: the image with the markers masked out is split into
  octave bands by differences of Gaussian blurs taken over the unmasked pixels only
  (normalised convolution), ``band_k = G(s_k) - G(2 s_k)`` for s_k = 0 (the image itself),
  1, 2, 4, 8 px, and the **low** part G(16 px) (wavelengths longer than about 100 px: the
  LED gradients). ``band_rms_grey`` holds the RMS of each band over the unmasked pixels
  (borders of 8 px excluded), finest first: their squares split the variance of the
  shading, i.e. its power spectrum in octaves (the finest band holds wavelengths of about
  2-6 px, each next one twice those). Colour: the **mean** B, G, R of the unmasked pixels
  and the **spread** (standard deviation) of each channel's low part across the image, and
  the correlation coefficients of the low parts between channels (B-G, B-R, G-R).
* **Noise**: Immerkaer's estimate, sqrt(pi / 2) times the mean absolute value of the image
  convolved with the kernel [[1, -2, 1], [-2, 4, -2], [1, -2, 1]] / 6 over the unmasked
  pixels, per channel, then the median of the channels (Immerkaer, "Fast noise variance
  estimation", CVIU 1996). The kernel removes anything locally linear, so this is pixel
  noise plus the finest texture; a median-based version would be quantised by the uint8
  grey levels (1/6 steps), so the mean is used.

A video's statistics are the median of its frames' (``summarise``).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import cv2
import numpy as np
from scipy.optimize import least_squares
from scipy.spatial import cKDTree
from scipy.special import ndtr

from drivers.sim.render.gel_analysis import OCTAVE_SIGMAS_PX, find_markers, grey_of, masked_blur

BAND_SIGMAS_PX = OCTAVE_SIGMAS_PX
"""Gaussian sigmas bounding the octave bands, px; the last is the low part's."""

BAND_NAMES = ("2-6px", "6-12px", "12-25px", "25-50px", "50-100px")
"""Approximate wavelengths each band holds (half-power points of the DoG filters)."""

BORDER_PX = 8
EDGE_TO_10_90 = 2 * 1.2815516  # 10-90 % width of a Gaussian-blurred step, in units of s
_IMMERKAER = np.array([[1, -2, 1], [-2, 4, -2], [1, -2, 1]], np.float32) / 6.0


@dataclass(frozen=True)
class AppearanceStats:
    """The statistics of one image (see the module docstring); NaN where nothing was
    measurable (no markers). Units: px, grey levels (0-255), darkness 0-1."""

    width_px: int
    height_px: int
    marker_count: int
    marker_pitch_px: float
    marker_diameter_px: float
    marker_darkness: float
    marker_edge_10_90_px: float
    mean_bgr: tuple[float, float, float]
    shading_spread_bgr: tuple[float, float, float]
    shading_correlation_bg_br_gr: tuple[float, float, float]
    band_rms_grey: tuple[float, ...]
    low_rms_grey: float
    noise_grey: float

    def as_dict(self) -> dict[str, object]:
        """JSON-ready: floats rounded to 4 digits, the bands keyed by wavelength."""
        out: dict[str, object] = {}
        for key, value in asdict(self).items():
            if key == "band_rms_grey":
                out[key] = {name: _round(v) for name, v in zip(BAND_NAMES, value, strict=True)}
            elif isinstance(value, tuple):
                out[key] = [_round(v) for v in value]
            else:
                out[key] = _round(value)
        return out


def _round(value: float) -> float | int | None:
    if isinstance(value, int):
        return value
    return None if not np.isfinite(value) else round(float(value), 4)


def measure(image: np.ndarray) -> AppearanceStats:
    """The statistics of a BGR uint8 image (H, W, 3) (a grey (H, W) one is taken as grey
    in all three channels)."""
    image = np.asarray(image)
    if image.ndim == 2:
        image = np.repeat(image[..., None], 3, axis=2)
    if image.ndim != 3 or image.shape[2] != 3 or min(image.shape[:2]) < 4 * BORDER_PX:
        raise ValueError(
            f"image: expected a BGR image (H, W, 3) of at least {4 * BORDER_PX} px a side, "
            f"got shape {image.shape}"
        )
    colour = image.astype(np.float32)
    grey = grey_of(colour)
    markers = find_markers(grey)
    free = ~markers.mask
    inner = np.zeros_like(free)
    inner[BORDER_PX:-BORDER_PX, BORDER_PX:-BORDER_PX] = True
    counted = free & inner
    background = masked_blur(grey, free, 3.0)
    pitch, diameter, darkness, edge = _marker_stats(grey, background, markers.centres_px)
    bands, low = _bands(grey, free, counted)
    low_colour = masked_blur(colour, free, BAND_SIGMAS_PX[-1])[counted]
    with np.errstate(invalid="ignore", divide="ignore"):  # a flat channel: NaN
        correlation = np.corrcoef(low_colour.T)
    return AppearanceStats(
        width_px=image.shape[1],
        height_px=image.shape[0],
        marker_count=len(markers.centres_px),
        marker_pitch_px=pitch,
        marker_diameter_px=diameter,
        marker_darkness=darkness,
        marker_edge_10_90_px=edge,
        mean_bgr=tuple(float(v) for v in colour[counted].mean(axis=0)),
        shading_spread_bgr=tuple(float(v) for v in low_colour.std(axis=0)),
        shading_correlation_bg_br_gr=tuple(
            float(correlation[i, j]) for i, j in ((0, 1), (0, 2), (1, 2))
        ),
        band_rms_grey=bands,
        low_rms_grey=low,
        noise_grey=_noise(colour, free & _eroded(inner)),
    )


def _eroded(mask: np.ndarray) -> np.ndarray:
    return cv2.erode(mask.astype(np.uint8), np.ones((3, 3), np.uint8)).astype(bool)


def _bands(
    grey: np.ndarray, free: np.ndarray, counted: np.ndarray
) -> tuple[tuple[float, ...], float]:
    levels = [grey] + [masked_blur(grey, free, s) for s in BAND_SIGMAS_PX[1:]]
    rms = tuple(
        float(np.sqrt(np.mean((fine - coarse)[counted] ** 2)))
        for fine, coarse in zip(levels[:-1], levels[1:], strict=True)
    )
    return rms, float(levels[-1][counted].std())


def _noise(colour: np.ndarray, counted: np.ndarray) -> float:
    sigmas = []
    for channel in cv2.split(colour):
        residual = cv2.filter2D(channel, cv2.CV_32F, _IMMERKAER)[counted]
        sigmas.append(np.sqrt(np.pi / 2) * np.mean(np.abs(residual)))
    return float(np.median(sigmas))


def _marker_stats(
    grey: np.ndarray, background: np.ndarray, centres: np.ndarray
) -> tuple[float, float, float, float]:
    if len(centres) < 2:
        return (np.nan,) * 4
    pitch = float(np.median(cKDTree(centres).query(centres, k=2)[0][:, 1]))
    reach = min(pitch / 2, 12.0)
    height, width = grey.shape
    ys, xs = np.mgrid[0:height, 0:width].astype(np.float64)
    fits = []
    for cx, cy in centres:
        if not (reach <= cx <= width - 1 - reach and reach <= cy <= height - 1 - reach):
            continue  # cut by the border
        x0, x1 = int(cx - reach), int(cx + reach) + 1
        y0, y1 = int(cy - reach), int(cy + reach) + 1
        r = np.hypot(xs[y0:y1, x0:x1] - cx, ys[y0:y1, x0:x1] - cy).ravel()
        near = r <= reach
        fits.append(
            _fit_edge(
                r[near], grey[y0:y1, x0:x1].ravel()[near], background[y0:y1, x0:x1].ravel()[near]
            )
        )
    if not fits:
        return pitch, np.nan, np.nan, np.nan
    radius, depth, softness = np.median(np.array(fits), axis=0)
    return pitch, float(2 * radius), float(depth), float(EDGE_TO_10_90 * softness)


def _fit_edge(r: np.ndarray, values: np.ndarray, background: np.ndarray) -> tuple:
    """(R px, d, s px) of ``values = b (1 - d Phi((R - r) / s))`` by least squares."""
    dark = values < background - 0.5 * (background - values.min())
    start = (max(np.sqrt(dark.sum() / np.pi), 1.0), 0.8, 0.7)

    def residual(p):
        radius, depth, softness = p
        return background * (1.0 - depth * ndtr((radius - r) / softness)) - values

    fit = least_squares(residual, start, bounds=([0.5, 0.0, 0.1], [r.max(), 1.0, 5.0]))
    return tuple(fit.x)


def table_rows(stats: AppearanceStats) -> dict[str, float]:
    """The statistics as named scalars, in a fixed order (tables, tests)."""
    rows = {
        "markers": float(stats.marker_count),
        "marker pitch px": stats.marker_pitch_px,
        "marker diameter px": stats.marker_diameter_px,
        "marker darkness": stats.marker_darkness,
        "marker edge 10-90 % px": stats.marker_edge_10_90_px,
    }
    for channel, mean, spread in zip("BGR", stats.mean_bgr, stats.shading_spread_bgr, strict=True):
        rows[f"mean {channel}"] = mean
        rows[f"shading spread {channel}"] = spread
    for pair, value in zip(("B-G", "B-R", "G-R"), stats.shading_correlation_bg_br_gr, strict=True):
        rows[f"shading correlation {pair}"] = value
    for name, value in zip(BAND_NAMES, stats.band_rms_grey, strict=True):
        rows[f"band {name} RMS"] = value
    rows["low part RMS"] = stats.low_rms_grey
    rows["noise"] = stats.noise_grey
    return rows


def format_table(columns: dict[str, AppearanceStats]) -> str:
    """A Markdown table: one row per statistic (``table_rows``), one column per image."""
    names = list(columns)
    tables = {name: table_rows(stats) for name, stats in columns.items()}
    lines = [
        "| statistic | " + " | ".join(names) + " |",
        "|---|" + "---:|" * len(names),
    ]
    for row in tables[names[0]]:
        cells = (_cell(tables[name][row]) for name in names)
        lines.append(f"| {row} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def _cell(value: float) -> str:
    if not np.isfinite(value):
        return "-"
    return f"{value:.0f}" if abs(value) >= 100 else f"{value:.3g}"


def summarise(stats: list[AppearanceStats]) -> AppearanceStats:
    """The median of several images' statistics (a video's frames), field by field, over the
    images where it was measurable (NaN if none)."""
    if not stats:
        raise ValueError("stats: expected at least one image's statistics")
    merged: dict[str, object] = {}
    for key, value in asdict(stats[0]).items():
        column = np.array([asdict(s)[key] for s in stats], dtype=float).reshape(len(stats), -1)
        median = [
            float(np.median(c[np.isfinite(c)])) if np.isfinite(c).any() else np.nan
            for c in column.T
        ]
        if isinstance(value, tuple):
            merged[key] = tuple(median)
        elif isinstance(value, int):
            merged[key] = int(round(median[0]))
        else:
            merged[key] = median[0]
    return AppearanceStats(**merged)
