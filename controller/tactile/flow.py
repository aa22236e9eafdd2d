"""From tactile images to a displacement field on the grid, in working-image pixels.

Three families, behind one small interface (``GridFlow``):

* ``DenseGridFlow``: dense optical flow (OpenCV DIS or Farneback) between the reference and
  the current image, on the luminance or on each colour channel (averaged), optionally on a
  downscaled image, then pooled to the grid by exact area mean (``cv2.INTER_AREA``).
* ``MarkerGridFlow``: the gel's printed markers, found once in the reference and tracked
  from it with pyramidal Lucas-Kanade at sub-pixel precision, then spread onto the grid by
  normalised Gaussian weights. Needs a marker gel (GelSight Mini), not a plain DIGIT.
* ``GridLKFlow`` (controller/tactile/grid_lk.py): the grid field fitted to every pixel of
  every channel at once by regularised Lucas-Kanade; for gels with or without markers.

All return ``(rows, cols, 2)`` displacements in pixels of the working image, [..., 0] along
x (columns) and [..., 1] along y (rows): the displacement of the gel point that was at the
cell in the reference. Images are BGR uint8 (H, W, 3) at the working resolution. Buffers are
allocated when the reference is set; per frame only OpenCV's own outputs are allocated.
"""

from __future__ import annotations

from typing import Protocol

import cv2
import numpy as np

from controller.tactile.grid_lk import GridLKFlow
from controller.tactile.settings import DisParams, FarnebackParams, FlowConfig, MarkerParams

_DIS_PRESETS = {
    "ultrafast": cv2.DISOPTICAL_FLOW_PRESET_ULTRAFAST,
    "fast": cv2.DISOPTICAL_FLOW_PRESET_FAST,
    "medium": cv2.DISOPTICAL_FLOW_PRESET_MEDIUM,
}


class GridFlow(Protocol):
    """Measures the grid displacement field of an image against a reference image."""

    def set_reference(self, image: np.ndarray) -> None: ...

    def measure(self, image: np.ndarray, out: np.ndarray) -> np.ndarray:
        """Write the (rows, cols, 2) displacement in px into ``out`` and return it."""
        ...


def make_grid_flow(config: FlowConfig, shape_hw: tuple[int, int], rows: int, cols: int) -> GridFlow:
    """The GridFlow that ``config.method`` names, for images of ``shape_hw`` = (H, W)."""
    if config.method == "markers":
        return MarkerGridFlow(config.markers, shape_hw, rows, cols, config.warm_start)
    if config.method == "grid_lk":
        return GridLKFlow(config, shape_hw, rows, cols)
    return DenseGridFlow(config, shape_hw, rows, cols)


def create_dis(params: DisParams) -> cv2.DISOpticalFlow:
    """An OpenCV DIS solver from its preset, with every non-null override applied."""
    dis = cv2.DISOpticalFlow.create(_DIS_PRESETS[params.preset])
    setters = {
        "finest_scale": dis.setFinestScale,
        "patch_size": dis.setPatchSize,
        "patch_stride": dis.setPatchStride,
        "gradient_descent_iterations": dis.setGradientDescentIterations,
        "variational_refinement_iterations": dis.setVariationalRefinementIterations,
        "variational_refinement_alpha": dis.setVariationalRefinementAlpha,
        "variational_refinement_delta": dis.setVariationalRefinementDelta,
        "variational_refinement_gamma": dis.setVariationalRefinementGamma,
        "use_mean_normalization": dis.setUseMeanNormalization,
        "use_spatial_propagation": dis.setUseSpatialPropagation,
    }
    for name, setter in setters.items():
        value = getattr(params, name)
        if value is not None:
            setter(value)
    return dis


class DenseGridFlow:
    """Dense optical flow pooled to the grid (see module docstring)."""

    def __init__(self, config: FlowConfig, shape_hw: tuple[int, int], rows: int, cols: int) -> None:
        if config.method not in ("dis", "farneback"):
            raise ValueError(
                f"DenseGridFlow needs method 'dis' or 'farneback', got {config.method!r}"
            )
        self.config = config
        self.rows, self.cols = rows, cols
        height, width = shape_hw
        self.flow_shape = (
            max(1, round(height * config.scale)),
            max(1, round(width * config.scale)),
        )
        n_channels = 3 if config.color == "per_channel" else 1
        self._reference = [np.empty(self.flow_shape, np.uint8) for _ in range(n_channels)]
        self._current = [np.empty(self.flow_shape, np.uint8) for _ in range(n_channels)]
        self._full = np.empty(shape_hw, np.uint8)
        self._flows = [np.zeros((*self.flow_shape, 2), np.float32) for _ in range(n_channels)]
        self._mean_flow = np.zeros((*self.flow_shape, 2), np.float32)
        self._pooled = np.empty((rows, cols, 2), np.float32)
        self._dis = create_dis(config.dis) if config.method == "dis" else None
        self._has_previous = False

    def set_reference(self, image: np.ndarray) -> None:
        self._split(image, self._reference)
        self._has_previous = False

    def dense(self, image: np.ndarray) -> np.ndarray:
        """Dense flow (h, w, 2) float32 in px of the (possibly downscaled) flow image."""
        self._split(image, self._current)
        warm = self.config.warm_start and self._has_previous
        for ref, cur, flow in zip(self._reference, self._current, self._flows, strict=True):
            if not warm:
                flow.fill(0.0)
            if self._dis is not None:
                self._dis.calc(ref, cur, flow)
            else:
                _farneback(ref, cur, flow, self.config.farneback, warm)
        self._has_previous = True
        if len(self._flows) == 1:
            return self._flows[0]
        np.add(self._flows[0], self._flows[1], out=self._mean_flow)
        for flow in self._flows[2:]:
            self._mean_flow += flow
        self._mean_flow *= 1.0 / len(self._flows)
        return self._mean_flow

    def pool(self, flow: np.ndarray, out: np.ndarray) -> np.ndarray:
        """Area-mean of ``flow`` over each grid cell, in px of the working image, into ``out``."""
        cv2.resize(flow, (self.cols, self.rows), dst=self._pooled, interpolation=cv2.INTER_AREA)
        np.multiply(self._pooled, 1.0 / self.config.scale, out=out)
        return out

    def measure(self, image: np.ndarray, out: np.ndarray) -> np.ndarray:
        return self.pool(self.dense(image), out)

    def _split(self, image: np.ndarray, planes: list[np.ndarray]) -> None:
        """Luminance or colour planes of ``image``, resized to the flow resolution."""
        resize = self.flow_shape != self._full.shape
        for channel, plane in enumerate(planes):
            target = self._full if resize else plane
            if len(planes) == 1:
                cv2.cvtColor(image, cv2.COLOR_BGR2GRAY, dst=target)
            else:
                cv2.extractChannel(image, channel, dst=target)
            if resize:
                size = (self.flow_shape[1], self.flow_shape[0])
                cv2.resize(self._full, size, dst=plane, interpolation=cv2.INTER_AREA)


def _farneback(
    ref: np.ndarray, cur: np.ndarray, flow: np.ndarray, p: FarnebackParams, warm: bool
) -> None:
    flags = cv2.OPTFLOW_FARNEBACK_GAUSSIAN if p.gaussian_window else 0
    if warm:
        flags |= cv2.OPTFLOW_USE_INITIAL_FLOW
    cv2.calcOpticalFlowFarneback(
        ref,
        cur,
        flow,
        p.pyr_scale,
        p.levels,
        p.winsize,
        p.iterations,
        p.poly_n,
        p.poly_sigma,
        flags,
    )


def detect_markers(gray: np.ndarray, params: MarkerParams) -> np.ndarray:
    """Centres (M, 2) float32 in px (x, y) of the dark markers in a grayscale image.

    The background is the image with the markers closed away (grey-level closing with a disk
    a little larger than the largest marker). A marker is a connected region darker than the
    background by more than Otsu's threshold on that darkness (which separates markers from
    the gel's texture) and at least ``detect_threshold`` grey levels, with an area in
    [min_area_px, max_area_px]. The centre is the darkness-weighted centroid.
    """
    radius = int(np.ceil(np.sqrt(params.max_area_px / np.pi))) + 2
    disk = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * radius + 1, 2 * radius + 1))
    background = cv2.morphologyEx(gray, cv2.MORPH_CLOSE, disk)
    darkness = cv2.subtract(background, gray)
    otsu, _ = cv2.threshold(darkness, 0, 255, cv2.THRESH_BINARY | cv2.THRESH_OTSU)
    mask = (darkness > max(otsu, params.detect_threshold)).astype(np.uint8)
    count, labels, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=8)
    areas = stats[1:, cv2.CC_STAT_AREA]
    keep = np.flatnonzero((areas >= params.min_area_px) & (areas <= params.max_area_px)) + 1
    if keep.size == 0:
        return np.empty((0, 2), np.float32)
    weights = darkness.astype(np.float64) * mask
    ys, xs = np.indices(gray.shape)
    index = labels.ravel()
    total = np.bincount(index, weights.ravel(), minlength=count)[keep]
    cx = np.bincount(index, (weights * xs).ravel(), minlength=count)[keep] / total
    cy = np.bincount(index, (weights * ys).ravel(), minlength=count)[keep] / total
    return np.stack([cx, cy], axis=1).astype(np.float32)


class MarkerGridFlow:
    """Marker tracking (see module docstring). ``warm_start`` starts each frame's search at
    the previous frame's positions instead of the reference positions."""

    def __init__(
        self,
        params: MarkerParams,
        shape_hw: tuple[int, int],
        rows: int,
        cols: int,
        warm_start: bool,
    ) -> None:
        self.params = params
        self.rows, self.cols = rows, cols
        self.warm_start = warm_start
        height, width = shape_hw
        self._cell_x = (np.arange(cols) + 0.5) * (width / cols)
        self._cell_y = (np.arange(rows) + 0.5) * (height / rows)
        self._sigma_px = params.smoothing_cells * max(width / cols, height / rows)
        self._reference = np.empty(shape_hw, np.uint8)
        self._current = np.empty(shape_hw, np.uint8)
        self._criteria = (
            cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS,
            params.max_iterations,
            0.005,
        )
        self.markers_px = np.empty((0, 2), np.float32)

    def set_reference(self, image: np.ndarray) -> None:
        cv2.cvtColor(image, cv2.COLOR_BGR2GRAY, dst=self._reference)
        markers = detect_markers(self._reference, self.params)
        if len(markers) < self.params.min_markers:
            raise ValueError(
                f"found {len(markers)} markers in the reference image, expected at least "
                f"{self.params.min_markers}; the 'markers' flow method needs a gel with printed "
                "markers (use method 'dis' otherwise) or a lower markers.detect_threshold"
            )
        self.markers_px = markers
        m = len(markers)
        self._p0 = markers.reshape(-1, 1, 2).copy()
        self._p1 = self._p0.copy()
        cell_x, cell_y = np.meshgrid(self._cell_x, self._cell_y)
        d2 = (cell_x.reshape(-1, 1) - markers[:, 0]) ** 2 + (
            cell_y.reshape(-1, 1) - markers[:, 1]
        ) ** 2
        self._weights = np.exp(-0.5 * d2 / self._sigma_px**2)  # (cells, markers)
        self._displacement = np.empty((m, 2))
        self._valid = np.empty(m)
        self._numerator = np.empty((self.rows * self.cols, 2))
        self._denominator = np.empty(self.rows * self.cols)
        self._tracked_once = False

    def measure(self, image: np.ndarray, out: np.ndarray) -> np.ndarray:
        cv2.cvtColor(image, cv2.COLOR_BGR2GRAY, dst=self._current)
        if not (self.warm_start and self._tracked_once):
            np.copyto(self._p1, self._p0)
        window = (self.params.window_px, self.params.window_px)
        _, status, _ = cv2.calcOpticalFlowPyrLK(
            self._reference,
            self._current,
            self._p0,
            self._p1,
            winSize=window,
            maxLevel=self.params.pyramid_levels,
            criteria=self._criteria,
            flags=cv2.OPTFLOW_USE_INITIAL_FLOW,
        )
        self._tracked_once = True
        np.subtract(self._p1[:, 0, :], self._p0[:, 0, :], out=self._displacement)
        np.copyto(self._valid, status[:, 0])
        self._displacement *= self._valid[:, None]
        np.matmul(self._weights, self._displacement, out=self._numerator)
        np.matmul(self._weights, self._valid, out=self._denominator)
        np.maximum(self._denominator, 1e-12, out=self._denominator)
        self._numerator /= self._denominator[:, None]
        out.reshape(-1, 2)[:] = self._numerator
        return out
