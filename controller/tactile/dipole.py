"""Tactile dipole moment and the tilt torque it gives (Fuchioka & Hamaya, ICRA 2024), continuous
under a net press.

Given the divergence ``div_i`` of the zeroed displacement field at grid points ``x_i`` (frame S,
mm), with N points, P = sum max(div, 0) and Q = sum max(-div, 0) the masses of the positive and
negative regions, C+ and C- their div-weighted centroids, and D = P - Q the net divergence:

1. the origin ``o``: with ``centroid_midpoint``, o = w m, the paper's midpoint
   m = (C+ + C-) / 2 scaled by a weight w that is 1 while the two regions are comparable
   (weak / strong mass ratio rho = min(P, Q) / max(P, Q) >= ``full_midpoint_ratio``) and
   falls smoothly to 0 (the gel centre) as the weaker region vanishes:
   w = smoothstep(rho / full_midpoint_ratio) = 3 t^2 - 2 t^3; with ``sensor_centre``, o = 0;
   with ``grasp_centroid``, o = c, the centre of the contact's support w measured once per
   grasp (``grasp_support``, set by ``set_grasp_support``), and until it is set (no
   open-gel frames, or no contact in the grasp) the ``centroid_midpoint`` rule;
2. p = (1/N) sum_i (x_i - o) div_i = (sum_i x_i div_i - o D) / N, in mm; with the grasp's
   support, p = (1/N) sum_i w_i (x_i - c) div_i: on a contact whose divergence is
   a + b (x - c) (a press a, a tilt b), the press drops out exactly, since c is w's centroid,
   and the noise of cells off the contact does not enter; p is linear in div, so
   |delta p| <= (2 R / N) sum_i |delta div_i| per axis;
3. tilt torque tau = [c_x p_y, -c_y p_x]; with c = 1 this is the raw torque in mm.

Why (docs/ARCHITECTURE.md, "The dipole under a net press"): sum_i (x_i - o) div_i is the
first moment of the divergence about o, which changes with o only through o D. With the
regions balanced (D = 0) every origin gives the same, translation-invariant moment
(P / N)(C+ - C-), the paper's. Under a net press (D != 0) the paper's moment is
((P + Q) / 2N)(C+ - C-): it is biased by the press and, when one region vanishes, its centroid
is undefined and the rule has no value (it used to return zero). The moment about the gel
centre stays the first moment of the pressure change about S's axes, the torque the wrench
is expressed about, and is linear in the field. Blending the origin between the two keeps the
paper's result where both regions are comparable and makes p continuous, indeed Lipschitz:
for any change of the divergence, per axis,
|delta p| <= (2 + 2.625 / full_midpoint_ratio) (R / N) sum_i |delta div_i|, R the grid's
largest |coordinate| on that axis (the weak region's centroid moves by up to R / Q per unit
change, and w D / Q stays below 1.125 / full_midpoint_ratio;
tests/controller/tactile/test_dipole_press.py).

Sign: pressure rising toward +y makes the gel spread there (div > 0 at +y, < 0 at -y), so
p_y > 0 and tau_x > 0: the torque about S's x axis that the gel exerts on the grasped object
(docs/ARCHITECTURE.md has the drawing).

Nothing here divides by the centroid distance. ``degenerate`` means the divergence is zero at
every point (no information about tilt; p is then zero), never NaN.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import numpy as np

from controller.tactile.field import require_finite

DipoleOrigin = Literal["centroid_midpoint", "sensor_centre", "grasp_centroid"]
DIPOLE_ORIGINS = ("centroid_midpoint", "sensor_centre", "grasp_centroid")
# An origin chosen by the caller (an experiment's candidate): (div, x, y) -> (o_x, o_y), with
# the divergence and the cell centres flattened (k,), x and y and the origin in mm, frame S.
OriginRule = Callable[[np.ndarray, np.ndarray, np.ndarray], tuple[float, float]]

# The weak / strong mass ratio from which on the paper's midpoint is used unchanged (the
# estimator configurations' ``dipole_full_midpoint_ratio``; docs/ARCHITECTURE.md says why).
FULL_MIDPOINT_RATIO = 0.25
# The grasp's support (``grasp_support``): a cell whose grasp divergence (of the press's own
# sign, relative to its largest value) is at most SUPPORT_LOW weighs 0, from SUPPORT_HIGH on
# 1, smoothly between (chosen on the real-gel check, seeds 0 and 1; docs/BENCHMARKS.md).
SUPPORT_LOW = 0.2
SUPPORT_HIGH = 0.7


@dataclass(frozen=True)
class DipoleMoment:
    """The dipole moment ``p`` (mm) and the origin ``m`` it was taken about (mm, frame S).

    ``midpoint_weight``: the share w of the centroid midpoint in that origin (1: the paper's
    midpoint; 0: the gel centre, when one sign of divergence is absent or with the
    ``sensor_centre`` origin, the grasp's contact centre with ``grasp_centroid``, or an
    ``OriginRule``'s origin).
    ``degenerate``: the divergence was zero everywhere (p is then zero)."""

    p_x: float
    p_y: float
    m_x: float
    m_y: float
    midpoint_weight: float
    degenerate: bool

    @property
    def tilt_torque_raw(self) -> tuple[float, float]:
        """(tau_x, tau_y) with c_x = c_y = 1, in mm: [p_y, -p_x]."""
        return self.p_y, -self.p_x


def midpoint_weight(ratio: float, full_ratio: float) -> float:
    """w(rho) = smoothstep(rho / full_ratio): 0 at rho = 0, 1 from rho = full_ratio on, with a
    continuous slope (at most 1.5 / full_ratio)."""
    if ratio >= full_ratio:
        return 1.0
    t = ratio / full_ratio
    return t * t * (3.0 - 2.0 * t)


@dataclass(frozen=True)
class GraspSupport:
    """Where the grasp touches, from its closing press: ``weights`` (rows, cols) in [0, 1] per
    grid cell and their centroid ``centre_mm`` (x, y), mm in frame S (``grasp_support``)."""

    weights: np.ndarray
    centre_mm: tuple[float, float]


def grasp_support(div: np.ndarray, x_mm: np.ndarray, y_mm: np.ndarray) -> GraspSupport | None:
    """The contact's support and centre from the divergence ``div`` (rows, cols) of the
    grasp's own field (the grasped gel against the open gel) on the grid ``x_mm`` (cols,) x
    ``y_mm`` (rows,); None if that divergence is zero everywhere.

    The closing press is one-signed and carries no tilt: its divergence is about uniform over
    the contact and falls to zero across the contact's edges, smeared over a cell or two.
    With d_i the divergence of the press's sign (the sign of the net divergence), relative to
    its largest value, w_i = smoothstep((d_i - SUPPORT_LOW) / (SUPPORT_HIGH - SUPPORT_LOW)):
    0 outside and on the outer edge, 1 in the contact's interior. The centre is
    sum w_i x_i / sum w_i (docs/ARCHITECTURE.md, "Under pushing")."""
    require_finite("grasp divergence", div)
    signed = div if float(div.sum()) >= 0.0 else -div
    peak = float(signed.max())
    if peak <= 0.0:
        return None
    t = np.clip((signed / peak - SUPPORT_LOW) / (SUPPORT_HIGH - SUPPORT_LOW), 0.0, 1.0)
    weights = t * t * (3.0 - 2.0 * t)
    total = float(weights.sum())
    centre = float(weights.sum(axis=0) @ x_mm) / total, float(weights.sum(axis=1) @ y_mm) / total
    return GraspSupport(weights, centre)


class DipoleMomentCalculator:
    """Computes the dipole moment on a fixed grid without allocating per call.

    ``x_mm`` (cols,) and ``y_mm`` (rows,) are the grid's cell centres in frame S;
    ``origin``: one of the rules of the module docstring, or an ``OriginRule`` (then
    p = (1/N) sum_i (x_i - o) div_i about the origin o it gives for each divergence);
    ``full_midpoint_ratio`` in (0, 1]: see the module docstring.
    """

    def __init__(
        self,
        x_mm: np.ndarray,
        y_mm: np.ndarray,
        origin: DipoleOrigin | OriginRule = "centroid_midpoint",
        full_midpoint_ratio: float = FULL_MIDPOINT_RATIO,
    ) -> None:
        if not callable(origin) and origin not in DIPOLE_ORIGINS:
            raise ValueError(
                f"dipole origin must be one of {', '.join(DIPOLE_ORIGINS)}, got {origin!r}"
            )
        if not 0.0 < full_midpoint_ratio <= 1.0:
            raise ValueError(f"full_midpoint_ratio must be in (0, 1], got {full_midpoint_ratio!r}")
        self.origin = origin
        self.full_midpoint_ratio = full_midpoint_ratio
        self.x_axis_mm = np.asarray(x_mm, float)
        self.y_axis_mm = np.asarray(y_mm, float)
        grid_x, grid_y = np.meshgrid(x_mm, y_mm)
        self._x = grid_x.ravel()
        self._y = grid_y.ravel()
        self._positive = np.empty_like(self._x)
        self._negative = np.empty_like(self._x)
        self.support: GraspSupport | None = None
        self._lever_x = np.empty_like(self._x)
        self._lever_y = np.empty_like(self._x)

    def set_grasp_support(self, support: GraspSupport | None) -> None:
        """The contact's support for the ``grasp_centroid`` rule (on this grid), or None to
        fall back to ``centroid_midpoint``. Ignored by the other rules."""
        if support is not None:
            weights = np.asarray(support.weights, float).reshape(-1)
            if weights.shape != self._x.shape:
                raise ValueError(
                    f"grasp support must have {self._x.size} grid values, got "
                    f"{np.shape(support.weights)}"
                )
            require_finite("grasp support", weights)
            c_x, c_y = support.centre_mm
            np.multiply(weights, self._x - c_x, out=self._lever_x)
            np.multiply(weights, self._y - c_y, out=self._lever_y)
        self.support = support

    def __call__(self, div: np.ndarray) -> DipoleMoment:
        """Dipole moment of ``div`` (rows, cols), dimensionless divergence of the field."""
        flat = div.reshape(-1)
        if flat.shape != self._x.shape:
            raise ValueError(
                f"divergence must have {self._x.size} grid values, got shape {div.shape}"
            )
        require_finite("divergence", flat)
        n = flat.size
        np.maximum(flat, 0.0, out=self._positive)
        np.minimum(flat, 0.0, out=self._negative)
        mass_pos = float(self._positive.sum())
        mass_neg = -float(self._negative.sum())
        moment_x = float(self._x @ flat)
        moment_y = float(self._y @ flat)
        degenerate = mass_pos + mass_neg == 0.0

        if callable(self.origin):
            o_x, o_y = self.origin(flat, self._x, self._y)
            np.subtract(self._x, o_x, out=self._lever_x)
            np.subtract(self._y, o_y, out=self._lever_y)
            p_x = float(self._lever_x @ flat) / n
            p_y = float(self._lever_y @ flat) / n
            return DipoleMoment(p_x, p_y, o_x, o_y, 0.0, degenerate)
        support = self.support if self.origin == "grasp_centroid" else None
        if support is not None:
            p_x = float(self._lever_x @ flat) / n
            p_y = float(self._lever_y @ flat) / n
            return DipoleMoment(p_x, p_y, *support.centre_mm, 0.0, degenerate)
        weight = 0.0
        if self.origin != "sensor_centre" and mass_pos > 0.0 and mass_neg > 0.0:
            ratio = min(mass_pos, mass_neg) / max(mass_pos, mass_neg)
            weight = midpoint_weight(ratio, self.full_midpoint_ratio)
        if weight == 0.0:
            return DipoleMoment(moment_x / n, moment_y / n, 0.0, 0.0, 0.0, degenerate)
        c_pos_x = float(self._x @ self._positive) / mass_pos
        c_pos_y = float(self._y @ self._positive) / mass_pos
        c_neg_x = -float(self._x @ self._negative) / mass_neg
        c_neg_y = -float(self._y @ self._negative) / mass_neg
        m_x = 0.5 * weight * (c_pos_x + c_neg_x)
        m_y = 0.5 * weight * (c_pos_y + c_neg_y)
        net = mass_pos - mass_neg
        # sum_i (x_i - m) div_i = sum_i x_i div_i - m * sum_i div_i
        p_x = (moment_x - m_x * net) / n
        p_y = (moment_y - m_y * net) / n
        return DipoleMoment(p_x, p_y, m_x, m_y, weight, False)
