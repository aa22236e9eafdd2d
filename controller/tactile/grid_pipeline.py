"""Everything after the flow, on one field grid: the grid displacement in px -> mm in frame S
(optional temporal EMA) -> NHHD (tau_z, shear, normal) -> the tilt dipole (on the grasp's
support, or on the configured grid; behind the no-contact gate unless the support came from
the open gel) and the FingerVision baseline
-> the slip detector. The estimator (controller/tactile/estimator.py) builds one per
reference; its buffers are allocated here, and a frame allocates only the estimate."""

from __future__ import annotations

import numpy as np

from controller.tactile.baseline import FingerVisionTorque
from controller.tactile.dipole import (
    DipoleMomentCalculator,
    GraspSupport,
    OriginRule,
    grasp_support,
)
from controller.tactile.field import VectorField
from controller.tactile.flow import GridFlow
from controller.tactile.nhhd import NHHD
from controller.tactile.noise_gate import NoiseGate
from controller.tactile.settings import EstimatorConfig
from controller.tactile.slip import RezeroPolicy, SlipDetector, SlipStatus
from controller.tactile.tilt_divergence import TiltDivergence
from controller.tactile.wrench import WrenchEstimate


class GridPipeline:
    """The stages after the flow for ``config`` on the field grid ``x_mm`` (cols,) x ``y_mm``
    (rows,), mm in frame S, at ``mm_per_px`` (the sensor profile's). ``origin``: the tilt
    dipole's moment origin (None: the configuration's ``dipole_origin``). Write each frame's
    displacement (rows, cols, 2) px into ``grid_px``, then call ``estimate``."""

    def __init__(
        self,
        config: EstimatorConfig,
        mm_per_px: float,
        x_mm: np.ndarray,
        y_mm: np.ndarray,
        origin: OriginRule | None = None,
    ) -> None:
        shape = (y_mm.size, x_mm.size)
        self.config = config
        self.x_mm, self.y_mm = x_mm, y_mm
        self.grid_px = np.zeros((*shape, 2))
        self.mm_per_px = mm_per_px
        self._u = np.zeros(shape)
        self._v = np.zeros(shape)
        self._work = np.empty(shape)
        self._magnitude = np.empty(shape)
        self._filtered = False
        self.nhhd = NHHD(x_mm, y_mm, config.tau_z_about)
        self.divergence = TiltDivergence(config, x_mm, y_mm, self.nhhd.dx, self.nhhd.dy)
        # the fallback's rule (the origin hook's if given); grasp_centroid's is below
        configured = config.dipole_origin
        rule = "centroid_midpoint" if configured == "grasp_centroid" else configured
        self.dipole = DipoleMomentCalculator(
            self.divergence.x_mm,
            self.divergence.y_mm,
            rule if origin is None else origin,
            config.dipole_full_midpoint_ratio,
        )
        self.grasp_dipole = DipoleMomentCalculator(x_mm, y_mm, "grasp_centroid")
        self.noise_gate: NoiseGate | None = None
        self.baseline = FingerVisionTorque(x_mm, y_mm)
        # A view on the field buffers, which every frame updates in place.
        self._field_view = VectorField(x_mm, y_mm, self._u, self._v)
        slip = config.slip
        self._slip = SlipDetector(slip, x_mm, y_mm) if slip.enabled else None

    @property
    def field(self) -> VectorField:
        """A copy of the latest (filtered) displacement field, mm in frame S."""
        return VectorField(self.x_mm, self.y_mm, self._u.copy(), self._v.copy())

    def update_field(self) -> None:
        """``grid_px`` -> mm in S, then the temporal EMA (alpha = weight of the newest
        field)."""
        scale = self.mm_per_px
        alpha = self.config.ema_alpha
        if alpha >= 1.0 or not self._filtered:
            np.multiply(self.grid_px[..., 0], scale, out=self._u)
            np.multiply(self.grid_px[..., 1], scale, out=self._v)
            self._filtered = True
            return
        for component, target in ((0, self._u), (1, self._v)):
            target *= 1.0 - alpha
            np.multiply(self.grid_px[..., component], alpha * scale, out=self._work)
            target += self._work

    def grasp_support(
        self, flow: GridFlow, grasp_image: np.ndarray, passes: int
    ) -> GraspSupport | None:
        """The contact's support from the grasp's own field: ``flow`` (set on the open gel)
        measured ``passes`` times on ``grasp_image``; None when no cell moved by more than
        ``contact_threshold_mm``. Leaves the field at zero."""
        for _ in range(passes):
            flow.measure(grasp_image, self.grid_px)
        self.update_field()
        np.hypot(self._u, self._v, out=self._magnitude)
        if float(self._magnitude.max()) > self.config.contact_threshold_mm:
            div = self.divergence.on_field(self.nhhd.decompose(self._u, self._v))
            support = grasp_support(div, self.x_mm, self.y_mm)
        else:
            support = None
        self._reset_field()
        return support

    def field_divergence(self) -> np.ndarray:
        """The divergence the grasp's dipole takes its moment of (the curl-free part's, or the
        raw field's, on the field grid; dimensionless, (rows, cols)) of the field last set by
        ``update_field``: a new array."""
        return self.divergence.on_field(self.nhhd.decompose(self._u, self._v)).copy()

    def divergence_map(self) -> np.ndarray:
        """The linear map (k, 2 n) from the field in px (n cells, row-major, x before y) to
        the fallback dipole's divergence (k values), probed column by column (it depends on
        the grid and the configuration only). Leaves the field at zero."""
        basis = np.zeros(self.grid_px.size)
        columns = []
        for index in range(basis.size):
            basis[index] = 1.0
            self.grid_px[...] = basis.reshape(self.grid_px.shape)
            self._filtered = False
            self.update_field()
            decomposition = (
                self.nhhd.decompose(self._u, self._v) if self.divergence.on_field_grid else None
            )
            div = self.divergence(self._u, self._v, decomposition)
            columns.append(div.ravel().copy())
            basis[index] = 0.0
        self._reset_field()
        return np.column_stack(columns)

    def _reset_field(self) -> None:
        self.grid_px.fill(0.0)
        self._u.fill(0.0)
        self._v.fill(0.0)
        self._filtered = False

    def estimate(
        self, t_s: float, rezero_policy: RezeroPolicy
    ) -> tuple[WrenchEstimate, SlipStatus | None]:
        """The uncalibrated estimate of the field last set by ``update_field``, at ``t_s``
        seconds, with the slip detector's status (None: disabled), which also advances
        ``rezero_policy``."""
        decomposition = self.nhhd.decompose(self._u, self._v)
        if self.grasp_dipole.support is not None:
            calculator, div = self.grasp_dipole, self.divergence.on_field(decomposition)
        else:
            calculator, div = self.dipole, self.divergence(self._u, self._v, decomposition)
        if self.noise_gate is not None:
            gated = (
                div
                if calculator is self.dipole
                else self.divergence(self._u, self._v, decomposition)
            )
            gate = self.noise_gate.until_contact(gated)
            if gate < 1.0:  # not in place: the buffer may be the decomposition's
                div = div * gate
        dipole = calculator(div)
        tau_x, tau_y = dipole.tilt_torque_raw
        fv_x, fv_y, fv_z = self.baseline(self._u, self._v)
        np.hypot(self._u, self._v, out=self._magnitude)
        contact = float(self._magnitude.mean()) > self.config.contact_threshold_mm
        status = None
        slip = gross = recommended = False
        if self._slip is not None:
            status = self._slip.update(self._field_view, decomposition, t_s)
            slip, gross = status.incipient, status.gross
            recommended = rezero_policy.update(status, t_s)
        estimate = WrenchEstimate(
            t_s=t_s,
            tau_x=tau_x,
            tau_y=tau_y,
            # The field follows the contact; the gel's wrench on the object opposes it.
            tau_z=-decomposition.tau_z,
            shear_x=-decomposition.shear_x,
            shear_y=-decomposition.shear_y,
            normal=decomposition.normal,
            fv_tau_x=fv_x,
            fv_tau_y=fv_y,
            # The baseline's in-plane torque is the field's curl too: negated like tau_z,
            # so both methods give one sign for one twist
            # (tests/controller/tactile/test_fv_sign.py).
            fv_tau_z=-fv_z,
            contact=contact,
            degenerate=dipole.degenerate,
            slip_suspected=slip,
            slip_gross=gross,
            rezero_recommended=recommended,
            zeroing=False,
            calibrated=False,
        )
        return estimate, status
