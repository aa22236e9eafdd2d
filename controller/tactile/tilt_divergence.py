"""The divergence the tilt dipole sees: of the raw field or of its NHHD curl-free part
(``divergence_of``), on the field's grid or on ``dipole_grid`` (the field block-averaged,
then decomposed on that coarser grid). Dimensionless, on cells whose centres are ``x_mm`` x
``y_mm`` (mm, frame S). Buffers are allocated once; a call allocates nothing."""

from __future__ import annotations

import numpy as np

from controller.tactile.field import block_mean, divergence
from controller.tactile.nhhd import CurlFreePart, NHHDResult
from controller.tactile.settings import EstimatorConfig, dipole_grid_mismatch


class TiltDivergence:
    """For a field on the grid ``x_mm`` (cols,) x ``y_mm`` (rows,), mm in frame S, with cell
    spacing ``dx_mm``, ``dy_mm`` (the NHHD's). Raises ValueError when ``dipole_grid`` does not
    divide the grid."""

    def __init__(
        self,
        config: EstimatorConfig,
        x_mm: np.ndarray,
        y_mm: np.ndarray,
        dx_mm: float,
        dy_mm: float,
    ) -> None:
        rows, cols = y_mm.size, x_mm.size
        self._raw = config.divergence_of == "raw"
        self._spacing_mm = (dx_mm, dy_mm)
        self._div = np.empty((rows, cols))
        self._work = np.empty((rows, cols))
        grid = config.dipole_grid
        if grid is None:
            self.block = (1, 1)
            self.x_mm, self.y_mm = x_mm, y_mm
            return
        mismatch = dipole_grid_mismatch(config, rows, cols)
        if mismatch:
            raise ValueError(mismatch)
        self.block = (rows // grid.rows, cols // grid.cols)
        self.x_mm = x_mm.reshape(grid.cols, -1).mean(axis=1)
        self.y_mm = y_mm.reshape(grid.rows, -1).mean(axis=1)
        coarse = (grid.rows, grid.cols)
        self._pooled = (np.empty(coarse), np.empty(coarse))
        self._coarse_div = np.empty(coarse)
        self._coarse_work = np.empty(coarse)
        self._coarse_curl_free = CurlFreePart(self.x_mm, self.y_mm)

    @property
    def on_field_grid(self) -> bool:
        """True when the dipole works on the field's own grid (no ``dipole_grid``)."""
        return self.block == (1, 1)

    def __call__(
        self, u_mm: np.ndarray, v_mm: np.ndarray, decomposition: NHHDResult | None
    ) -> np.ndarray:
        """The divergence of the field (``u_mm``, ``v_mm``: (rows, cols), mm) on the dipole's
        grid; ``decomposition``, the field's NHHD, is needed only on the field's grid. The
        result may be a buffer of the decomposition's or of this object's: do not modify it."""
        if self.on_field_grid:
            if decomposition is None:
                raise ValueError("the divergence on the field's grid needs the field's NHHD")
            return self.on_field(decomposition)
        block = self.block
        u = block_mean(u_mm, block, self._pooled[0])
        v = block_mean(v_mm, block, self._pooled[1])
        if not self._raw:
            u, v = self._coarse_curl_free(u, v)
        dx, dy = block[1] * self._spacing_mm[0], block[0] * self._spacing_mm[1]
        return divergence(u, v, dx, dy, self._coarse_div, self._coarse_work)

    def on_field(self, decomposition: NHHDResult) -> np.ndarray:
        """The divergence of the raw field or of its curl-free part on the field's grid."""
        if self._raw:
            return decomposition.div
        dx, dy = self._spacing_mm
        return divergence(decomposition.d_u, decomposition.d_v, dx, dy, self._div, self._work)
