"""An independent elastic model of the gel's surface: Boussinesq's half-space.

Not the project's gel model (drivers/sim/gel): a linear-elastic half-space under a normal
pressure ``p`` (Pa, pressing into the gel) on its surface. By Boussinesq's solution (Johnson,
*Contact Mechanics*, 1985, eq. 3.19a and 3.21) a normal point load ``P`` at the origin moves
the surface point at in-plane distance ``r`` radially by

    u_r = -(1 - 2 nu) (1 + nu) P / (2 pi E r)         (toward the load for nu < 1/2),

so a distributed pressure moves the surface in-plane by the convolution

    u(x) = -c  integral  p(xi) (x - xi) / |x - xi|^2  dxi,   c = (1 - 2 nu)(1 + nu) / (2 pi E).

The kernel is the gradient of ln|x|, whose Laplacian is 2 pi delta: the field is curl-free,
its divergence is exactly -2 pi c p (the surface contracts where it is pressed, by an amount
proportional to the local pressure) and it is harmonic, but not zero, outside the contact.

Lengths here are in pixels of the image grid and every field is linear in ``p``, so the
material constants only set the scale; callers scale the fields to a chosen displacement in
px. The integral is a discrete convolution over the pixels (pixel-area quadrature, the
kernel's principal value 0 at its own pixel), done with FFTs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.signal import fftconvolve


def halfspace_inplane_px(pressure: np.ndarray) -> np.ndarray:
    """In-plane surface displacement (H, W, 2) [x, y] of a pressure map (H, W) on the pixel
    grid, in units where c = 1 and the pixel is the unit of length (see module docstring).
    """
    height, width = pressure.shape
    dy, dx = np.mgrid[1 - height : height, 1 - width : width].astype(np.float64)
    r2 = dx**2 + dy**2
    r2[height - 1, width - 1] = np.inf  # the kernel's own pixel: principal value 0
    rows = slice(height - 1, 2 * height - 1)
    cols = slice(width - 1, 2 * width - 1)
    u = -fftconvolve(pressure, dx / r2, mode="full")[rows, cols]
    v = -fftconvolve(pressure, dy / r2, mode="full")[rows, cols]
    return np.stack([u, v], axis=-1)


@dataclass(frozen=True)
class ContactPatch:
    """A flat rectangular contact on the image grid, in px: centre (``cx``, ``cy``) and half
    sizes (``half_w``, ``half_h``), edges anti-aliased over one pixel."""

    cx: float
    cy: float
    half_w: float
    half_h: float

    def mask(self, height: int, width: int) -> np.ndarray:
        """Covered fraction (H, W) of each pixel, in [0, 1]."""
        y, x = np.mgrid[0:height, 0:width].astype(np.float64)
        in_x = np.clip(self.half_w + 0.5 - np.abs(x - self.cx), 0.0, 1.0)
        in_y = np.clip(self.half_h + 0.5 - np.abs(y - self.cy), 0.0, 1.0)
        return in_x * in_y


@dataclass(frozen=True)
class PressureBasis:
    """The three pressure maps a tilted flat contact is a sum of, and their surface fields.

    ``pressure = n * uniform + a_x * grad_y + a_y * grad_x`` where ``uniform`` is the contact
    mask, and ``grad_y`` / ``grad_x`` rise linearly across it (from -1 at one edge to +1 at
    the other, along y and along x). ``fields`` holds the matching in-plane displacements
    (3, H, W, 2), from ``halfspace_inplane_px`` (c = 1).

    ``tilt_moments`` (2, 2): the tilt torques of the two gradient maps, per unit weight, about
    the patch centre, as (tau_x, tau_y) in px^3 per unit pressure: tau_x = sum p (y - cy)
    (pressure rising toward +y), tau_y = -sum p (x - cx). Row 0 is ``grad_y``'s, row 1
    ``grad_x``'s.
    """

    uniform: np.ndarray
    grad_y: np.ndarray
    grad_x: np.ndarray
    fields: np.ndarray
    tilt_moments: np.ndarray

    @classmethod
    def for_patch(cls, patch: ContactPatch, height: int, width: int) -> PressureBasis:
        mask = patch.mask(height, width)
        y, x = np.mgrid[0:height, 0:width].astype(np.float64)
        rel_x = (x - patch.cx) / patch.half_w
        rel_y = (y - patch.cy) / patch.half_h
        grad_y = mask * rel_y
        grad_x = mask * rel_x
        fields = np.stack([halfspace_inplane_px(p) for p in (mask, grad_y, grad_x)])
        moments = np.array(
            [
                [float((grad_y * (y - patch.cy)).sum()), -float((grad_y * (x - patch.cx)).sum())],
                [float((grad_x * (y - patch.cy)).sum()), -float((grad_x * (x - patch.cx)).sum())],
            ]
        )
        return cls(mask, grad_y, grad_x, fields, moments)
