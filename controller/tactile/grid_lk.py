"""Regularised Lucas-Kanade on the grid: one displacement per grid cell, fitted to every pixel.

The gel's displacement is smooth and the estimator needs it only on its grid, so instead of
a dense flow that is then pooled, this fits the grid field to the images directly: a
parametric Lucas-Kanade (Baker & Matthews, "Lucas-Kanade 20 years on", IJCV 2004) whose
motion model is one displacement ``u_k`` (px) per grid cell, with the membrane prior of Horn
& Schunck (1981) between neighbouring cells:

    minimise  sum_k sum_{x in cell k} sum_channels (I_cur(x + u_k) - I_ref(x))^2
              + lambda * sum_{neighbouring cells k, l} |u_k - u_l|^2.

Gauss-Newton, linearised with the reference's gradient ``g`` (fourth-order central
differences; inverse compositional: the normal matrix depends on the reference only, so it
is factorised once per reference). Each step solves ``(G + lambda L) du = -b - lambda L u``:
G is block diagonal with the cell means
of ``g g^T`` (summed over channels), b holds the cell means of ``g r``, r being the current
image warped back by the estimate minus the reference, and L is the Laplacian of the grid
graph. ``lambda = smoothness * mean(trace of G's blocks) / 2``: the prior's weight follows
the image's contrast, so one ``smoothness`` suits gels of any contrast. Every pixel of every
channel contributes in proportion to its gradient, so LED shading, fine texture and markers
all count, and a textureless cell is filled in from its neighbours instead of returning
noise. Working on each colour channel matters on a real gel: its shading gradients differ per
channel and partly cancel in the luminance.

``normalize_brightness``: each cell also gets a free brightness offset per channel,
eliminated in closed form (the gradient and the residual are centred on their cell means),
so a drifting LED does not read as motion; it costs the information in each cell's mean
gradient. Images are blurred by ``blur_sigma_px`` first (less noise, a wider linear range).

``noise_covariance(noise_grey, operator)``: the covariance of a linear function of the
estimate under white camera noise, propagated
through the normal equations (docs/ARCHITECTURE.md, "Quiet before contact"): with noise of
variance s^2 in both images, each cell's ``b`` has covariance 2 s^2 G_k / N_k (N_k pixels; the
blur leaves the sum of the noise's autocorrelation at s^2), so the field's is
``2 s^2 (G + lambda L)^-1 diag(G_k / N_k) (G + lambda L)^-1``.

``warm_start`` starts each frame from the previous frame's field instead of zero: the steps
then refine a nearly converged estimate (the tilt changes little between frames), which
matters for motions of several px, where one linearisation about zero falls short.

Per frame: one conversion to float, the blur, and per step a warp (bilinear; from the second
step, or from the first with ``warm_start``), two products and two area means per gradient
component, and a sparse solve. Displacements are in px of the working image, like every
``GridFlow``'s.
"""

from __future__ import annotations

import functools

import cv2
import numpy as np
from scipy import sparse
from scipy.sparse.linalg import factorized

from controller.tactile.settings import FlowConfig

# Ridge added to the normal matrix, relative to its mean data weight: keeps it invertible on
# a featureless image (whose field is then zero).
_RIDGE = 1e-6
# Fourth-order central difference, d/dx = (f[-2] - 8 f[-1] + 8 f[1] - f[2]) / 12 (as a
# correlation kernel): the 3-tap difference underestimates the gradient of sharp content, and
# each Gauss-Newton step then overshoots.
_DERIVATIVE = np.array([1.0, -8.0, 0.0, 8.0, -1.0], np.float32) / 12.0
_IDENTITY = np.array([1.0], np.float32)
# OpenCV's BGR -> grey weights: the luminance's noise variance is their squared sum times a
# channel's.
_GREY_NOISE_GAIN = 0.114**2 + 0.587**2 + 0.299**2


def grid_laplacian(rows: int, cols: int) -> sparse.csr_matrix:
    """Graph Laplacian (rows*cols square, cells in row-major order) of the 4-neighbour grid:
    u^T L u is the sum of squared differences between neighbouring cells."""
    index = np.arange(rows * cols).reshape(rows, cols)
    first = np.concatenate([index[:, :-1].ravel(), index[:-1, :].ravel()])
    second = np.concatenate([index[:, 1:].ravel(), index[1:, :].ravel()])
    n = rows * cols
    adjacency = sparse.coo_matrix((np.ones(first.size), (first, second)), shape=(n, n))
    adjacency = (adjacency + adjacency.T).tocsr()
    degree = np.asarray(adjacency.sum(axis=1)).ravel()
    return (sparse.diags(degree) - adjacency).tocsr()


@functools.lru_cache(maxsize=8)
def grid_prior(rows: int, cols: int) -> sparse.csr_matrix:
    """The membrane prior's matrix on the field (rows*cols cells, x before y in each):
    ``grid_laplacian`` acting on each component. A constant of the grid, built once per
    process (a flow is built per reference); do not modify it."""
    return sparse.kron(grid_laplacian(rows, cols), sparse.identity(2), format="csr")


def normal_matrix(
    blocks: np.ndarray, prior_weight: float, rows: int, cols: int
) -> sparse.csr_matrix:
    """``G + prior_weight * L`` (module docstring): the block-diagonal ``G`` of ``blocks``
    (rows*cols, 2, 2) plus the weighted ``grid_prior``. Built as a block-sparse matrix (a
    fraction of a millisecond; ``sparse.block_diag`` of the blocks takes about one)."""
    n = len(blocks)
    block_diagonal = sparse.bsr_matrix((blocks, np.arange(n), np.arange(n + 1)))
    return block_diagonal.tocsr() + prior_weight * grid_prior(rows, cols)


@functools.lru_cache(maxsize=8)
def pixel_grid(height: int, width: int) -> np.ndarray:
    """Each pixel's (x, y) coordinates, float32 (height, width, 2), read-only."""
    grid_y, grid_x = np.mgrid[0:height, 0:width].astype(np.float32)
    grid = np.stack([grid_x, grid_y], axis=2)
    grid.flags.writeable = False
    return grid


class GridLKFlow:
    """The grid field by regularised Lucas-Kanade (module docstring); a ``GridFlow``.

    Buffers are allocated here and when the reference is set; per frame only OpenCV's and
    the sparse solver's outputs are."""

    def __init__(self, config: FlowConfig, shape_hw: tuple[int, int], rows: int, cols: int) -> None:
        if config.method != "grid_lk":
            raise ValueError(f"GridLKFlow needs method 'grid_lk', got {config.method!r}")
        self.config = config
        self.params = config.grid_lk
        self.rows, self.cols = rows, cols
        height, width = shape_hw
        h = max(1, round(height * config.scale))
        w = max(1, round(width * config.scale))
        self.flow_shape = (h, w)
        self._gray = config.color == "gray"
        plane = (h, w) if self._gray else (h, w, 3)
        self._small = np.empty(plane, np.uint8)
        self._grey_full = np.empty(shape_hw, np.uint8)
        self._reference = np.empty(plane, np.float32)
        self._current = np.empty(plane, np.float32)
        self._warped = np.empty(plane, np.float32)
        self._residual = np.empty(plane, np.float32)
        self._product = np.empty(plane, np.float32)
        cells = (rows, cols) if self._gray else (rows, cols, 3)
        self._pooled = np.empty(cells, np.float32)
        self._pooled_centre = np.empty(cells, np.float32)
        self._residual_cells = np.empty(cells, np.float32)
        self._grid = pixel_grid(h, w)
        self._map = np.empty((h, w, 2), np.float32)  # the dense field, then x + u(x)
        self._field = np.empty((rows, cols, 2), np.float32)
        n = rows * cols
        self._blocks = np.zeros((n, 2, 2))
        self._theta = np.zeros((n, 2))
        self._rhs = np.empty((n, 2))
        self._term = np.empty(n)
        self._has_previous = False

    # -- images ------------------------------------------------------------------------------

    def _prepare(self, image: np.ndarray, out: np.ndarray) -> np.ndarray:
        """``image`` (BGR uint8, working resolution) as float32 grey or BGR at the flow
        resolution, blurred, into ``out``."""
        source = image
        if self._gray:
            cv2.cvtColor(image, cv2.COLOR_BGR2GRAY, dst=self._grey_full)
            source = self._grey_full
        if source.shape[:2] != self.flow_shape:
            size = (self.flow_shape[1], self.flow_shape[0])
            cv2.resize(source, size, dst=self._small, interpolation=cv2.INTER_AREA)
            source = self._small
        np.copyto(out, source, casting="unsafe")
        sigma = self.params.blur_sigma_px * self.config.scale
        if sigma > 0:
            cv2.GaussianBlur(out, (0, 0), sigma, dst=out)
        return out

    def _cell_means(self, plane: np.ndarray, out: np.ndarray) -> np.ndarray:
        """Area mean of ``plane`` over each grid cell, per channel, into ``out``."""
        size = (self.cols, self.rows)
        return cv2.resize(plane, size, dst=out, interpolation=cv2.INTER_AREA)

    def _moment(self, a: np.ndarray, b: np.ndarray, a_cells, b_cells, out: np.ndarray) -> None:
        """Cell means of a*b summed over channels into ``out`` (rows*cols,); given the cell
        means of a and b (brightness normalisation), of (a - mean a)(b - mean b)."""
        np.multiply(a, b, out=self._product)
        pooled = self._cell_means(self._product, self._pooled)
        if a_cells is not None:
            pooled -= np.multiply(a_cells, b_cells, out=self._pooled_centre)
        np.sum(pooled.reshape(self.rows * self.cols, -1), axis=1, out=out)

    # -- GridFlow ----------------------------------------------------------------------------

    def set_reference(self, image: np.ndarray) -> None:
        reference = self._prepare(image, self._reference)
        self._gradients = (
            cv2.sepFilter2D(reference, cv2.CV_32F, _DERIVATIVE, _IDENTITY),
            cv2.sepFilter2D(reference, cv2.CV_32F, _IDENTITY, _DERIVATIVE),
        )
        # the gradients' cell means, None without brightness normalisation
        self._gradient_cells: tuple[np.ndarray | None, ...]
        if self.params.normalize_brightness:
            self._gradient_cells = tuple(
                self._cell_means(g, np.empty_like(self._pooled)) for g in self._gradients
            )
        else:
            self._gradient_cells = (None, None)
        blocks = self._blocks
        for i in range(2):
            for j in range(i, 2):
                self._moment(
                    self._gradients[i],
                    self._gradients[j],
                    self._gradient_cells[i],
                    self._gradient_cells[j],
                    self._term,
                )
                blocks[:, i, j] = blocks[:, j, i] = self._term
        self._data_blocks = blocks.copy()
        weight = max(float(np.trace(blocks, axis1=1, axis2=2).mean()) / 2.0, 1e-12)
        blocks[:, 0, 0] += _RIDGE * weight
        blocks[:, 1, 1] += _RIDGE * weight
        matrix = normal_matrix(blocks, self.params.smoothness * weight, self.rows, self.cols)
        self._solve = factorized(matrix.tocsc())
        self._has_previous = False

    def noise_covariance(self, noise_grey: float, operator: np.ndarray) -> np.ndarray:
        """Covariance (k, k) of ``operator @ field`` under white camera noise of
        ``noise_grey`` grey levels (standard deviation per channel) in the reference and the
        current image (module docstring). ``operator`` (k, 2 n) acts on the field this flow
        returns (px of the working image; cells in row-major order, x before y). Needs a
        reference; k solves with the factorised normal matrix."""
        variance = noise_grey**2 * (_GREY_NOISE_GAIN if self._gray else 1.0)
        variance *= self.config.scale**2  # resizing to the flow resolution averages pixels
        pixels = self.flow_shape[0] * self.flow_shape[1] / (self.rows * self.cols)
        # The field in working px is theta / scale; the matrix is symmetric.
        rows = np.asarray(operator, float) / self.config.scale
        solved = np.stack([self._solve(row) for row in rows]).reshape(len(rows), -1, 2)
        data = np.einsum("knj,nij,lni->kl", solved, self._data_blocks, solved)
        return (2.0 * variance / pixels) * data

    def _warp_back(self, current: np.ndarray) -> np.ndarray:
        """``current`` sampled at x + u(x), u the estimate interpolated bilinearly between
        cell centres, into the warped buffer."""
        np.copyto(self._field, self._theta.reshape(self.rows, self.cols, 2), casting="unsafe")
        size = (self.flow_shape[1], self.flow_shape[0])
        cv2.resize(self._field, size, dst=self._map, interpolation=cv2.INTER_LINEAR)
        # one two-channel map (x, y): the same sampling as two one-channel maps, one pass
        np.add(self._map, self._grid, out=self._map)
        cv2.remap(  # type: ignore[call-overload]  # OpenCV's stubs miss map2=None (one map)
            current,
            self._map,
            None,
            cv2.INTER_LINEAR,
            dst=self._warped,
            borderMode=cv2.BORDER_REPLICATE,
        )
        return self._warped

    def measure(self, image: np.ndarray, out: np.ndarray) -> np.ndarray:
        current = self._prepare(image, self._current)
        warm = self.config.warm_start and self._has_previous
        if not warm:
            self._theta.fill(0.0)
        normalize = self.params.normalize_brightness
        for step in range(self.params.iterations):
            moved = warm or step > 0
            source = self._warp_back(current) if moved else current
            np.subtract(source, self._reference, out=self._residual)
            residual_cells = (
                self._cell_means(self._residual, self._residual_cells) if normalize else None
            )
            for axis in range(2):
                self._moment(
                    self._gradients[axis],
                    self._residual,
                    self._gradient_cells[axis],
                    residual_cells,
                    self._term,
                )
                np.negative(self._term, out=self._rhs[:, axis])
            if moved:
                # The step du solves (G + lambda L) du = -b - lambda L u, so the new estimate
                # u + du solves (G + lambda L) (u + du) = G u - b: add G u.
                for i in range(2):
                    for j in range(2):
                        np.multiply(self._blocks[:, i, j], self._theta[:, j], out=self._term)
                        self._rhs[:, i] += self._term
            np.copyto(self._theta, self._solve(self._rhs.ravel()).reshape(-1, 2))
        self._has_previous = True
        np.multiply(self._theta.reshape(self.rows, self.cols, 2), 1.0 / self.config.scale, out=out)
        return out
