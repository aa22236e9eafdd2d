"""Surface displacement of the gel layer under contact tractions, and what the camera sees.

Green's functions: the Boussinesq and Cerruti solutions for a point load on an elastic
half-space (Johnson, *Contact Mechanics*, 1985, eqs. 3.19 and 3.22), each multiplied by
``exp(-r / h)``. The factor stands for the rigid window the layer of thickness ``h`` is
bonded to, which confines the deformation to a few thicknesses around the load (the exact
layer solution decays exponentially too, but is a Hankel-transform integral we do not need).
With ``E``, ``nu`` and a point force (P normal, Q tangential) at the origin, at distance r:

* normal displacement toward the camera: ``(1 - nu^2) / (pi E) P / r``;
* tangential displacement along Q: ``(1 + nu) / (pi E) [(1 - nu) / r + nu x^2 / r^3] Q``,
  across it ``(1 + nu) / (pi E) nu x y / r^3 Q``;
* radial displacement under P, toward the load: ``(1 - 2 nu)(1 + nu) / (2 pi E) P / r``.

Tractions are cell forces spread over a cell; the ``1/r`` singularity at a cell's own centre
is replaced by its mean over the cell. The convolution is one FFT per load component and one
per displacement component on the zero-padded grid (batched in one call each way).

The same kernels fix the stiffness of the contact model, so that the two agree on a uniform
load: the mean compliance of a large uniformly loaded area is ``2 (1 - nu^2) h / E`` normal
and ``(1 + nu)(2 - nu) h / E`` tangential (the integrals of the kernels).

Camera: a pinhole ``D`` from the gel surface on S's z axis. A surface point displaced by
``u`` in-plane and by ``w`` toward the camera is seen at ``(r + u) D / (D - w)``; to first
order the image displacement is ``u + r w / D``.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import fft

from drivers.sim.gel.footprint import PhysicsGrid
from drivers.sim.gel.profile import GelProfile

_MEAN_INVERSE_DISTANCE = 4.0 * math.log(1.0 + math.sqrt(2.0))  # mean of 1/r over a unit square


class ElasticLayer:
    """Gel surface displacement from contact tractions on ``grid`` (see the module docstring)."""

    def __init__(self, profile: GelProfile, grid: PhysicsGrid) -> None:
        self.profile, self.grid = profile, grid
        e, nu, h = profile.young_modulus_pa, profile.poisson_ratio, profile.thickness_m
        self.normal_compliance_m_pa = 2.0 * (1.0 - nu**2) * h / e
        self.shear_compliance_m_pa = (1.0 + nu) * (2.0 - nu) * h / e
        rows, cols = grid.shape
        self._fft_shape = (fft.next_fast_len(2 * rows - 1), fft.next_fast_len(2 * cols - 1))
        self._kernels = self._kernel_spectra(e, nu, h)

    def _kernel_spectra(self, e: float, nu: float, h: float) -> dict[str, np.ndarray]:
        rows, cols = self.grid.shape
        cell = self.grid.cell_m
        dy, dx = np.meshgrid(
            (np.arange(-rows + 1, rows)) * cell, (np.arange(-cols + 1, cols)) * cell, indexing="ij"
        )
        r = np.hypot(dx, dy)
        centre = r == 0
        r_safe = np.where(centre, 1.0, r)
        decay = np.exp(-r / h)
        inv_r = np.where(centre, _MEAN_INVERSE_DISTANCE / cell, 1.0 / r_safe) * decay
        # Cell means at the centre: x^2/r^3 and y^2/r^3 average half of 1/r; the odd ones 0.
        xx = np.where(centre, 0.5 * inv_r, dx * dx / r_safe**3 * decay)
        yy = np.where(centre, 0.5 * inv_r, dy * dy / r_safe**3 * decay)
        xy = np.where(centre, 0.0, dx * dy / r_safe**3 * decay)
        rx = np.where(centre, 0.0, dx / r_safe**2 * decay)
        ry = np.where(centre, 0.0, dy / r_safe**2 * decay)
        kernels = {
            "n": (1 - nu**2) / (math.pi * e) * inv_r,
            "xx": (1 + nu) / (math.pi * e) * ((1 - nu) * inv_r + nu * xx),
            "yy": (1 + nu) / (math.pi * e) * ((1 - nu) * inv_r + nu * yy),
            "xy": (1 + nu) / (math.pi * e) * nu * xy,
            # Radial pull toward the load: displacement at r is -c P r_vec / r^2.
            "px": -(1 - 2 * nu) * (1 + nu) / (2 * math.pi * e) * rx,
            "py": -(1 - 2 * nu) * (1 + nu) / (2 * math.pi * e) * ry,
        }
        # The kernels act on cell forces (N): the self-term is already the cell mean.
        return {name: fft.rfft2(k, self._fft_shape, workers=1) for name, k in kernels.items()}

    def surface_displacement_m(
        self, pressure_force_n: np.ndarray, shear_force_n: np.ndarray
    ) -> np.ndarray:
        """(rows, cols, 3) displacement of the gel surface: in-plane x, y and toward the
        camera, m. ``pressure_force_n``: normal force each cell takes from the object, N,
        pushing the gel toward the camera; ``shear_force_n``: in-plane force each cell
        takes from the object, N (rows, cols, 2)."""
        rows, cols = self.grid.shape
        loads = np.empty((3, rows, cols))
        loads[0], loads[1:] = pressure_force_n, np.moveaxis(shear_force_n, -1, 0)
        p, qx, qy = fft.rfft2(loads, self._fft_shape, workers=1)  # one batched transform
        k = self._kernels
        spectra = np.empty((3, *p.shape), complex)
        np.multiply(k["xx"], qx, out=spectra[0])
        spectra[0] += k["xy"] * qy
        spectra[0] += k["px"] * p
        np.multiply(k["xy"], qx, out=spectra[1])
        spectra[1] += k["yy"] * qy
        spectra[1] += k["py"] * p
        np.multiply(k["n"], p, out=spectra[2])
        full = fft.irfft2(spectra, self._fft_shape, workers=1)
        out = np.empty((rows, cols, 3))
        for i in range(3):
            out[..., i] = full[i, rows - 1 : 2 * rows - 1, cols - 1 : 2 * cols - 1]
        return out

    def image_field_px(self, surface_m: np.ndarray) -> np.ndarray:
        """The forward image displacement the camera sees, px, on the view's cells
        (view rows, view cols, 2): ``u + r w / D`` (see the module docstring)."""
        view = self.grid.view
        u = surface_m[view]
        x, y = self.grid.x_m[view], self.grid.y_m[view]
        magnification = u[..., 2] / self.profile.camera_distance_m
        px_per_m = 1e3 / self.profile.mm_per_px
        field = np.empty((*x.shape, 2))
        field[..., 0] = (u[..., 0] + x * magnification) * px_per_m
        field[..., 1] = (u[..., 1] + y * magnification) * px_per_m
        return field
