"""Natural Helmholtz-Hodge decomposition (NHHD) of a grid field, by FFT convolution.

Bhatia, Pascucci & Bremer, "The Natural Helmholtz-Hodge Decomposition for Open-Boundary Flow
Analysis", IEEE TVCG 2014; used for tactile force and torque by Zhang et al., RA-L 2019.

For a field v on the grid (frame S, mm), the decomposition is v = d + r + h with

* D = G * div v, d = grad D               -- curl-free, "diverging" part;
* R = G * curl v, r = (-dR/dy, dR/dx)     -- divergence-free, "rotational" part;
* h = v - d - r                            -- harmonic part, holds the translation.

G(x) = ln|x| / (2 pi) is the free-space Green's function of the 2-D Laplacian, so the
potentials need no boundary conditions (the "natural" choice). The convolution is a sum over
grid cells of area dx*dy; on the cell itself, where ln|x| is singular, G takes its mean over
the cell (see ``greens_self_term``). Potentials are in mm^2, parts in mm.

The convolution of an R x C grid with the (2R-1) x (2C-1) kernel is exact (no wrap-around)
when embedded in a 2R x 2C circular FFT, so one call costs O(N log N) for N = R*C points.

Derived quantities (raw units, to be scaled by calibration):

* ``tau_z``: in-plane torque of the rotational part, (1/N) sum_i [(x_i - c) x r_i]_z in mm^2,
  positive for rotation from +x toward +y. The origin c is the gel centre (``tau_z_about``
  "gel_centre", the default: the axis the wrench is expressed about) or the extremum c_R of
  R, the centre of rotation (``"rotation_centre"``, as Zhang et al.). The extremum jumps from
  cell to cell and moves with shear and tilt, so a torque about it mixes those in: on the
  simulated jig (docs/EVALUATION.md) it lowers R^2 under tilt pulses and shear.
* ``shear``: the mean of h, in mm (translation of the contact).
* ``normal``: the mean outward radial component of d about the extremum c_D of D, in mm;
  positive when the gel spreads (more pressure) relative to the zeroed reference.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Literal

import numpy as np

from controller.tactile.field import d_dx, d_dy, divergence, require_finite

_SELF_TERM_SAMPLES = 256


def greens_self_term(dx: float, dy: float) -> float:
    """Mean of ln(r)/(2 pi) over a dx x dy cell centred on the singularity (mm grid).

    Midpoint quadrature on a 256 x 256 sub-grid (the singularity is integrable and never
    sampled); accurate to about 1e-5 relative, and computed once per grid.
    """
    s = (np.arange(_SELF_TERM_SAMPLES) + 0.5) / _SELF_TERM_SAMPLES - 0.5
    gx, gy = np.meshgrid(s * dx, s * dy)
    return float(np.log(np.hypot(gx, gy)).mean() / (2.0 * np.pi))


def greens_kernel(rows: int, cols: int, dx: float, dy: float) -> np.ndarray:
    """G at all grid offsets, as a (2*rows, 2*cols) circular array: entry [m mod 2R, n mod 2C]
    holds G at offset (m*dy, n*dx) for |m| < rows, |n| < cols; the other entries are zero."""
    m = np.arange(-(rows - 1), rows)
    n = np.arange(-(cols - 1), cols)
    off_y, off_x = np.meshgrid(m * dy, n * dx, indexing="ij")
    r = np.hypot(off_x, off_y)
    r[rows - 1, cols - 1] = 1.0
    g = np.log(r) / (2.0 * np.pi)
    g[rows - 1, cols - 1] = greens_self_term(dx, dy)
    kernel = np.zeros((2 * rows, 2 * cols))
    kernel[np.ix_(m % (2 * rows), n % (2 * cols))] = g
    return kernel


@functools.lru_cache(maxsize=16)
def greens_spectrum(rows: int, cols: int, dx: float, dy: float) -> np.ndarray:
    """``rfft2`` of ``greens_kernel`` times the cell area (mm^2), read-only: a constant of
    the grid, built once per process (an estimator builds a decomposer per reference)."""
    spectrum = np.fft.rfft2(greens_kernel(rows, cols, dx, dy)) * (dx * dy)
    spectrum.flags.writeable = False
    return spectrum


@functools.lru_cache(maxsize=16)
def greens_matrix(rows: int, cols: int, dx: float, dy: float) -> np.ndarray:
    """The dense (N, N) Green's matrix of the grid, N = rows * cols, times the cell area
    (mm^2), read-only: ``greens_matrix @ s.ravel()`` is the NHHD's convolution of the source
    ``s`` (rows, cols), cells in row-major order. A constant of the grid, built once."""
    kernel = greens_kernel(rows, cols, dx, dy) * (dx * dy)
    r, c = np.divmod(np.arange(rows * cols), cols)
    matrix = kernel[(r[:, None] - r[None, :]) % (2 * rows), (c[:, None] - c[None, :]) % (2 * cols)]
    matrix.flags.writeable = False
    return matrix


@dataclass(frozen=True)
class NHHDResult:
    """Parts, potentials and derived quantities of one decomposition.

    The arrays are (rows, cols) views into the decomposer's buffers: they are overwritten by
    the next call, so copy them to keep them.
    """

    d_u: np.ndarray
    d_v: np.ndarray
    r_u: np.ndarray
    r_v: np.ndarray
    h_u: np.ndarray
    h_v: np.ndarray
    potential_d: np.ndarray
    potential_r: np.ndarray
    div: np.ndarray
    curl: np.ndarray
    tau_z: float
    shear_x: float
    shear_y: float
    normal: float
    rotation_centre_mm: tuple[float, float]
    source_centre_mm: tuple[float, float]


class NHHD:
    """Natural HHD on a fixed rows x cols grid with spacing (dx, dy) mm and cell centres
    ``x_mm`` (cols,), ``y_mm`` (rows,) in frame S. Buffers and the kernel's FFT are built once;
    ``decompose`` allocates no arrays."""

    def __init__(
        self,
        x_mm: np.ndarray,
        y_mm: np.ndarray,
        tau_z_about: Literal["gel_centre", "rotation_centre"] = "gel_centre",
    ) -> None:
        if tau_z_about not in ("gel_centre", "rotation_centre"):
            raise ValueError(
                f"tau_z_about must be 'gel_centre' or 'rotation_centre', got {tau_z_about!r}"
            )
        self.tau_z_about = tau_z_about
        self.rows, self.cols = y_mm.size, x_mm.size
        self.dx = float(x_mm[1] - x_mm[0])
        self.dy = float(y_mm[1] - y_mm[0])
        self.x_mm, self.y_mm = x_mm, y_mm
        self._grid_x, self._grid_y = np.meshgrid(x_mm, y_mm)
        shape = (self.rows, self.cols)
        padded = (2 * self.rows, 2 * self.cols)
        self._kernel_spectrum = greens_spectrum(*shape, self.dx, self.dy)
        self._sources = np.zeros((2, *padded))  # [div, curl], zero-padded
        self._spectrum = np.empty((2, padded[0], padded[1] // 2 + 1), dtype=complex)
        self._potentials = np.empty((2, *padded))
        stacked = (2, *shape)
        self._uv = np.empty(stacked)  # [u, v]
        self._field_dx = np.empty(stacked)  # [du/dx, dv/dx]
        self._field_dy = np.empty(stacked)  # [du/dy, dv/dy]
        self._potential_dx = np.empty(stacked)  # [dD/dx, dR/dx]
        self._potential_dy = np.empty(stacked)  # [dD/dy, dR/dy]
        self._buffers = {k: np.empty(shape) for k in ("hu", "hv", "w")}
        self._lever_x = np.empty(shape)
        self._lever_y = np.empty(shape)
        self._radius = np.empty(shape)

    def decompose(self, u: np.ndarray, v: np.ndarray) -> NHHDResult:
        """Decompose the field (u, v), each (rows, cols) in mm."""
        if u.shape != (self.rows, self.cols) or v.shape != u.shape:
            raise ValueError(
                f"field components must have shape {(self.rows, self.cols)}, "
                f"got {u.shape} and {v.shape}"
            )
        uv = self._uv
        np.copyto(uv[0], u)
        np.copyto(uv[1], v)
        require_finite("displacement field", uv)
        b = self._buffers
        rows, cols = self.rows, self.cols
        # Derivatives of both components (and below, of both potentials) in one call each.
        gx = d_dx(uv, self.dx, self._field_dx)
        gy = d_dy(uv, self.dy, self._field_dy)
        div = np.add(gx[0], gy[1], out=self._sources[0, :rows, :cols])
        rot = np.subtract(gx[1], gy[0], out=self._sources[1, :rows, :cols])

        np.fft.rfft2(self._sources, out=self._spectrum)
        self._spectrum *= self._kernel_spectrum
        # irfft2(out=...) does not write into ``out`` for 2-D transforms (NumPy 2.x), so invert
        # one axis at a time: complex ifft over rows in place, then the real inverse over columns.
        np.fft.ifft(self._spectrum, axis=-2, out=self._spectrum)
        np.fft.irfft(self._spectrum, n=self._sources.shape[-1], axis=-1, out=self._potentials)
        potentials = self._potentials[:, :rows, :cols]
        pot_d, pot_r = potentials[0], potentials[1]

        pgx = d_dx(potentials, self.dx, self._potential_dx)
        pgy = d_dy(potentials, self.dy, self._potential_dy)
        d_u, d_v = pgx[0], pgy[0]  # d = grad D
        r_u, r_v = np.negative(pgy[1], out=pgy[1]), pgx[1]  # r = (-dR/dy, dR/dx)
        np.subtract(u, d_u, out=b["hu"])
        b["hu"] -= r_u
        np.subtract(v, d_v, out=b["hv"])
        b["hv"] -= r_v

        n = rows * cols
        rotation_centre = self._extremum(pot_r, rot)
        self._levers(rotation_centre if self.tau_z_about == "rotation_centre" else (0.0, 0.0))
        tau_z = (float(np.vdot(self._lever_x, r_v)) - float(np.vdot(self._lever_y, r_u))) / n
        source_centre = self._extremum(pot_d, div)
        self._levers(source_centre)
        normal = self._mean_radial(d_u, d_v)
        return NHHDResult(
            d_u=d_u,
            d_v=d_v,
            r_u=r_u,
            r_v=r_v,
            h_u=b["hu"],
            h_v=b["hv"],
            potential_d=pot_d,
            potential_r=pot_r,
            div=div,
            curl=rot,
            tau_z=tau_z,
            shear_x=float(b["hu"].mean()),
            shear_y=float(b["hv"].mean()),
            normal=normal,
            rotation_centre_mm=rotation_centre,
            source_centre_mm=source_centre,
        )

    def _extremum(self, potential: np.ndarray, source: np.ndarray) -> tuple[float, float]:
        """Grid position (x, y) mm of the potential's extremum. G grows with distance, so a
        positive source sits in a well (minimum) and a negative one under a peak (maximum).
        The sign is that of sum(s |s|), which follows the strongest sources: a contact's
        core, not the weaker opposite-signed ring around it whose total nearly cancels it."""
        np.abs(source, out=self._buffers["w"])
        dominant = float(np.vdot(source, self._buffers["w"]))
        flat = potential.argmin() if dominant >= 0.0 else potential.argmax()
        row, col = divmod(int(flat), self.cols)
        return float(self.x_mm[col]), float(self.y_mm[row])

    def _levers(self, centre: tuple[float, float]) -> None:
        np.subtract(self._grid_x, centre[0], out=self._lever_x)
        np.subtract(self._grid_y, centre[1], out=self._lever_y)

    def _mean_radial(self, du: np.ndarray, dv: np.ndarray) -> float:
        """Mean of d . (x - c)/|x - c| over the grid, using (and consuming) the current levers;
        the point at the centre has a zero lever and contributes nothing."""
        np.hypot(self._lever_x, self._lever_y, out=self._radius)
        np.maximum(self._radius, 1e-12 * self.dx, out=self._radius)
        self._lever_x /= self._radius
        self._lever_y /= self._radius
        return (float(np.vdot(self._lever_x, du)) + float(np.vdot(self._lever_y, dv))) / du.size


class CurlFreePart:
    """The NHHD's curl-free part alone, d = grad(G * div v), on a fixed grid (as ``NHHD``).

    For callers that need no other part, on small grids: the convolution is one product with
    a dense (N, N) Green's matrix, N = rows * cols (the same sum over cells as ``NHHD``'s FFT,
    which is faster only for large grids). ``__call__`` allocates no arrays."""

    def __init__(self, x_mm: np.ndarray, y_mm: np.ndarray) -> None:
        rows, cols = y_mm.size, x_mm.size
        self.dx = float(x_mm[1] - x_mm[0])
        self.dy = float(y_mm[1] - y_mm[0])
        self._green = greens_matrix(rows, cols, self.dx, self.dy)
        shape = (rows, cols)
        self._div = np.empty(shape)
        self._work = np.empty(shape)
        self._potential = np.empty(shape)
        self._d_u = np.empty(shape)
        self._d_v = np.empty(shape)

    def __call__(self, u: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(d_u, d_v) mm for the field (u, v) mm, as views into this object's buffers."""
        div = divergence(u, v, self.dx, self.dy, self._div, self._work)
        np.matmul(self._green, div.reshape(-1), out=self._potential.reshape(-1))
        return d_dx(self._potential, self.dx, self._d_u), d_dy(self._potential, self.dy, self._d_v)
