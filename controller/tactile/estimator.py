"""The estimation pipeline: ``push(frame, t_s) -> WrenchEstimate``.

frame (uint8 BGR or grey) -> working image -> grid displacement (px, vs the zeroed reference)
-> mm in frame S -> optional temporal EMA -> NHHD (tau_z, shear, normal) -> dipole (tau_x,
tau_y) and the FingerVision baseline -> slip detector and re-zero policy (flags) -> optional
calibration.

Zeroing: the reference is the mean of ``reference_frames`` frames, captured from the frames
pushed after ``rezero()`` (or on the first frames if no reference was ever set), or set
directly with ``set_reference(frames)``. While it is being captured, ``push`` returns zero
estimates flagged ``zeroing``.

The open gel: ``capture_open()`` (the next pushed frames) or ``set_open_reference(frames)``
stores the gel as it looks with the gripper open. Each reference set afterwards then also
gives the grasp's own field (the reference against the open gel), from which the
``grasp_centroid`` dipole origin takes the contact's support and centre
(dipole.grasp_support); without
an open gel, or with no contact between it and the reference (no grid cell moved by more
than ``contact_threshold_mm``), that origin falls back to ``centroid_midpoint``. In a grasp::

    est.capture_open(n)   # gripper open, gel free: the next n pushed frames
    ...                   # close and settle (pushes return zeroing estimates)
    est.rezero(n)         # the next n frames: the grasp reference and the contact centre

After gross slip the re-zero policy raises
``rezero_recommended`` once the load is released and the field has settled; with
``slip.rezero.auto`` the estimator then starts capturing a new reference itself.

Frames may come in either orientation (e.g. 240 x 320 from a DIGIT) and at any size with
the sensor profile's aspect ratio; they are resized to the profile's resolution in their own
orientation, where ``mm_per_px`` applies. Every later frame must have the reference's shape.

All buffers are allocated when the reference is set; a push allocates only what OpenCV
must (its flow outputs) and the returned estimate.
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

import cv2
import numpy as np

from controller.tactile.baseline import FingerVisionTorque
from controller.tactile.calibration import Calibration
from controller.tactile.dipole import DipoleMomentCalculator, GraspSupport, grasp_support
from controller.tactile.field import VectorField, block_mean, divergence, grid_axes_mm
from controller.tactile.flow import GridFlow, make_grid_flow
from controller.tactile.grid_lk import GridLKFlow
from controller.tactile.nhhd import NHHD, CurlFreePart, NHHDResult
from controller.tactile.noise_gate import NoiseGate
from controller.tactile.settings import (
    EstimatorConfig,
    dipole_grid_mismatch,
    field_grid,
    sensor_estimator,
)
from controller.tactile.slip import RezeroPolicy, RezeroState, SlipDetector, SlipStatus
from controller.tactile.wrench import WrenchEstimate
from core.sensor_profile import SensorProfile, sensor_profile

_ASPECT_TOLERANCE = 0.02
MAX_REFERENCE_FRAMES = 10_000
# Flow passes from the open gel to the grasp (each warm-started from the last): the grasp
# moves the gel by several px, more than one linearisation of grid_lk covers.
GRASP_FLOW_PASSES = 4


def estimator_for_sensor(
    sensor: SensorProfile | str | Path,
    estimator: str | Path | None = None,
    calibration: Calibration | None = None,
) -> TactileEstimator:
    """The estimator for ``sensor`` (a profile, or a name in configs/sensors/ or a YAML path)
    with the configuration ``estimator`` (a name in configs/estimators/ or a YAML path; None:
    the profile's own ``estimator:``), optionally calibrated. A configuration that does not
    suit the sensor (marker tracking without printed markers, a ``dipole_grid`` that does not
    divide the field grid) is a ConfigError naming both; so is a missing or invalid file."""
    profile = sensor if isinstance(sensor, SensorProfile) else sensor_profile(str(sensor))
    name, config = sensor_estimator(profile, None if estimator is None else str(estimator))
    return TactileEstimator(config, profile, calibration, config_name=name)


class TactileEstimator:
    """Frame-to-wrench pipeline for one sensor (see module docstring). ``config_name``: the
    configuration's name or YAML path, for reports (``estimator_for_sensor`` sets it; None for
    a configuration built in code)."""

    def __init__(
        self,
        config: EstimatorConfig,
        profile: SensorProfile,
        calibration: Calibration | None = None,
        config_name: str | None = None,
    ) -> None:
        self.config = config
        self.profile = profile
        self.calibration = calibration
        self.config_name = config_name
        self._frame_shape: tuple[int, ...] | None = None
        self._zeroing_left = 0
        self._reference_sum: np.ndarray | None = None
        self._zeroing_count = 0
        self._grid_flow: GridFlow | None = None
        self._slip: SlipDetector | None = None
        self._last_slip: SlipStatus | None = None
        self._rezero_policy = RezeroPolicy(config.slip.rezero)
        self._open_image: np.ndarray | None = None
        self._open_shape: tuple[int, ...] | None = None
        self._open_left = 0
        self._open_sum: np.ndarray | None = None
        self._open_count = 0
        self._awaiting_rezero = False
        self._contact_centre: tuple[float, float] | None = None
        self._noise_gate: NoiseGate | None = None
        self._divergence_map_cache: tuple[object, np.ndarray] | None = None

    # -- reference ---------------------------------------------------------------------------

    @property
    def is_zeroed(self) -> bool:
        """True once a reference exists and is not being re-captured."""
        return self._grid_flow is not None and self._zeroing_left == 0

    def rezero(self, n_frames: int | None = None) -> None:
        """Capture a new reference from the next ``n_frames`` pushed frames (default: the
        configuration's ``reference_frames``). Call it after the grasp has settled.

        Raises ValueError, leaving the estimator as it was, unless ``n_frames`` is a whole
        number in [1, MAX_REFERENCE_FRAMES] (a bool, a float or NaN is refused)."""
        n = self._frame_count("rezero", n_frames)
        self._open_left = 0
        self._awaiting_rezero = False
        self._zeroing_left = n
        self._zeroing_count = 0
        self._reference_sum = None
        self._rezero_policy.reset()

    def capture_open(self, n_frames: int | None = None) -> None:
        """Capture the open gel (gripper open, nothing touching) from the next ``n_frames``
        pushed frames (default: ``reference_frames``); call ``rezero`` once the grasp has
        settled. The current reference is dropped: until the next reference exists, ``push``
        returns zero estimates flagged ``zeroing`` (it does not zero by itself on the
        closing gripper). Raises ValueError as ``rezero`` does."""
        n = self._frame_count("capture_open", n_frames)
        self._open_left = n
        self._open_count = 0
        self._open_sum = None
        self._zeroing_left = 0
        self._grid_flow = None
        self._contact_centre = None
        self._awaiting_rezero = True

    def set_open_reference(self, frames: np.ndarray | Sequence[np.ndarray] | None) -> None:
        """Use the mean of ``frames`` as the open gel (module docstring), None to forget it.
        Takes effect when the next reference is set (``rezero`` or ``set_reference``); the
        reference must then have the open frames' size. On a ValueError (as
        ``set_reference``) the estimator is left as it was."""
        if frames is None:
            self._open_image = self._open_shape = None
            return
        mean, shape = self._mean_image(frames, "open")
        self._open_image = np.clip(np.rint(mean), 0, 255).astype(np.uint8)
        self._open_shape = shape
        self._open_left = 0

    @property
    def contact_centre_mm(self) -> tuple[float, float] | None:
        """The contact's centre (x, y) in mm, frame S, measured from the grasp against the
        open gel when the reference was set; None without an open gel or contact."""
        return self._contact_centre

    def _frame_count(self, what: str, n_frames: int | None) -> int:
        n = self.config.reference_frames if n_frames is None else n_frames
        if (
            isinstance(n, bool)
            or not isinstance(n, numbers.Integral)
            or not 1 <= n <= MAX_REFERENCE_FRAMES
        ):
            raise ValueError(
                f"{what} needs a whole number of frames in [1, {MAX_REFERENCE_FRAMES}], "
                f"got {n!r}"
            )
        return int(n)

    def set_reference(self, frames: np.ndarray | Sequence[np.ndarray]) -> None:
        """Use the mean of ``frames`` (one image, or a sequence / stack of images) now.

        Every frame is checked before anything changes: on a ValueError (no frame, a frame
        that is not an image, frames of different sizes, or of another size than the open
        gel's) the estimator is left as it was."""
        mean, shape = self._mean_image(frames, "reference")
        self._install_reference(mean, shape)
        self._frame_shape = shape
        self._zeroing_left = 0
        self._open_left = 0
        self._awaiting_rezero = False

    def _mean_image(
        self, frames: np.ndarray | Sequence[np.ndarray], what: str
    ) -> tuple[np.ndarray, tuple[int, ...]]:
        """The mean working image of ``frames`` (float32) and their (rows, cols)."""
        stack = [frames] if isinstance(frames, np.ndarray) and frames.ndim <= 3 else list(frames)
        if not stack:
            raise ValueError(f"the {what} needs at least one frame")
        shape = None
        total = None
        for index, frame in enumerate(stack):
            try:
                image = self._working_image(frame, shape)
            except ValueError as exc:
                raise ValueError(f"{what} frame {index}: {exc}") from None
            shape = frame.shape[:2]
            total = image.astype(np.float32) if total is None else total + image
        return total / len(stack), shape

    def _install_reference(self, mean_image: np.ndarray, shape: tuple[int, ...]) -> None:
        """Build the flow on the reference first, then replace the buffers: a ValueError
        leaves the estimator as it was. ``shape``: the frames' (rows, cols)."""
        if self._open_image is not None and self._open_shape != shape:
            raise ValueError(
                f"frame of {shape[1]} x {shape[0]} px does not match the open gel's frames "
                f"({self._open_shape[1]} x {self._open_shape[0]} px)"
            )
        # Round half to even: the mean of 2 integer frames ends in .5 half the time, and
        # rounding those up would brighten the reference by 0.25 grey levels, which dense
        # flow on a smooth gel reads as motion.
        reference = np.clip(np.rint(mean_image), 0, 255).astype(np.uint8)
        height, width = reference.shape[:2]
        rows, cols = field_grid(self.config, height, width)
        mismatch = dipole_grid_mismatch(self.config, rows, cols)
        if mismatch:
            raise ValueError(mismatch)
        grid_flow = make_grid_flow(self.config.flow, (height, width), rows, cols)
        grid_flow.set_reference(reference)
        self._allocate(height, width, rows, cols)
        support = self._grasp_support(reference)
        self._grasp_dipole.set_grasp_support(support)
        self._contact_centre = None if support is None else support.centre_mm
        self._noise_gate = None if support is not None else self._make_noise_gate(grid_flow)
        self._grid_flow = grid_flow
        self._rezero_policy.reset()
        self._last_slip = None

    def _grasp_support(self, reference: np.ndarray) -> GraspSupport | None:
        """The contact's support from the grasp's field (``reference`` against the open gel)
        on the field's grid, or None (no open gel, no contact, no ``grasp_centroid``)."""
        if self._open_image is None or self.config.dipole_origin != "grasp_centroid":
            return None
        rows, cols = self._u.shape
        flow_config = replace(self.config.flow, warm_start=True)
        flow = make_grid_flow(flow_config, reference.shape[:2], rows, cols)
        flow.set_reference(self._open_image)
        for _ in range(GRASP_FLOW_PASSES):
            flow.measure(reference, self._grid_px)
        self._update_field()
        np.hypot(self._u, self._v, out=self._magnitude)
        if float(self._magnitude.max()) > self.config.contact_threshold_mm:
            div = self._field_divergence(self._nhhd.decompose(self._u, self._v))
            support = grasp_support(div, self.x_mm, self.y_mm)
        else:
            support = None
        self._grid_px.fill(0.0)
        self._u.fill(0.0)
        self._v.fill(0.0)
        self._filtered = False
        return support

    def _make_noise_gate(self, grid_flow: GridFlow) -> NoiseGate | None:
        """The no-contact gate (controller/tactile/noise_gate.py) of the fallback dipole's
        divergence, from ``grid_flow``'s noise (None: no ``noise_gate`` configured)."""
        settings = self.config.noise_gate
        if settings is None or not isinstance(grid_flow, GridLKFlow):
            return None
        key = (self._u.shape, tuple(self.x_mm), tuple(self.y_mm))
        if self._divergence_map_cache is None or self._divergence_map_cache[0] != key:
            self._divergence_map_cache = (key, self._divergence_map())
        covariance = grid_flow.noise_covariance(settings.noise_grey, self._divergence_map_cache[1])
        if not float(np.abs(covariance).max()) > 0.0:  # a featureless image: the field is 0
            return None
        return NoiseGate(covariance, settings.false_alarm)

    def _divergence_map(self) -> np.ndarray:
        """The linear map (k, 2 n) from the field in px (n cells, row-major, x before y) to
        the fallback dipole's divergence (k values), probed column by column (computed once
        per grid: the map depends on the grid and the configuration only)."""
        rows, cols = self._u.shape
        basis = np.zeros(2 * rows * cols)
        columns = []
        for index in range(basis.size):
            basis[index] = 1.0
            self._grid_px[...] = basis.reshape(rows, cols, 2)
            self._filtered = False
            self._update_field()
            decomposition = (
                self._nhhd.decompose(self._u, self._v) if self._dipole_block == (1, 1) else None
            )
            div = self._tilt_divergence(decomposition)
            columns.append(div.ravel().copy())
            basis[index] = 0.0
        self._grid_px.fill(0.0)
        self._u.fill(0.0)
        self._v.fill(0.0)
        self._filtered = False
        return np.column_stack(columns)

    def _allocate(self, height: int, width: int, rows: int, cols: int) -> None:
        x_mm, y_mm = grid_axes_mm(width, height, cols, rows, self.profile.mm_per_px)
        self.x_mm, self.y_mm = x_mm, y_mm
        self._grid_px = np.zeros((rows, cols, 2))
        self._u = np.zeros((rows, cols))
        self._v = np.zeros((rows, cols))
        self._div = np.empty((rows, cols))
        self._work = np.empty((rows, cols))
        self._magnitude = np.empty((rows, cols))
        self._filtered = False
        self._nhhd = NHHD(x_mm, y_mm, self.config.tau_z_about)
        self._allocate_dipole(x_mm, y_mm)
        self._baseline = FingerVisionTorque(x_mm, y_mm)
        # A view on the field buffers, which every push updates in place.
        self._field_view = VectorField(x_mm, y_mm, self._u, self._v)
        slip = self.config.slip
        self._slip = SlipDetector(slip, x_mm, y_mm) if slip.enabled else None

    def _allocate_dipole(self, x_mm: np.ndarray, y_mm: np.ndarray) -> None:
        """The dipole's grid: the field's, or ``dipole_grid`` (blocks of the field's cells);
        with ``grasp_centroid`` that is the fallback's, the grasp's dipole is on the field's
        grid (its support set when a reference is)."""
        self._grasp_dipole = DipoleMomentCalculator(x_mm, y_mm, "grasp_centroid")
        grid = self.config.dipole_grid
        rows, cols = y_mm.size, x_mm.size
        if grid is None:
            self._dipole_block = (1, 1)
            self._dipole = self._dipole_calculator(x_mm, y_mm)
            return
        mismatch = dipole_grid_mismatch(self.config, rows, cols)
        if mismatch:
            raise ValueError(mismatch)
        self._dipole_block = (rows // grid.rows, cols // grid.cols)
        x_coarse = x_mm.reshape(grid.cols, -1).mean(axis=1)
        y_coarse = y_mm.reshape(grid.rows, -1).mean(axis=1)
        self._dipole = self._dipole_calculator(x_coarse, y_coarse)
        coarse = (grid.rows, grid.cols)
        self._pooled = (np.empty(coarse), np.empty(coarse))
        self._coarse_div = np.empty(coarse)
        self._coarse_work = np.empty(coarse)
        self._coarse_curl_free = CurlFreePart(x_coarse, y_coarse)

    def _dipole_calculator(self, x_mm: np.ndarray, y_mm: np.ndarray) -> DipoleMomentCalculator:
        """The dipole on the grid ``x_mm`` x ``y_mm`` with the configuration's origin rule."""
        config = self.config
        origin = config.dipole_origin
        if origin == "grasp_centroid":  # its fallback; the grasp's dipole is _grasp_dipole
            origin = "centroid_midpoint"
        return DipoleMomentCalculator(x_mm, y_mm, origin, config.dipole_full_midpoint_ratio)

    def _tilt_divergence(self, decomposition: NHHDResult | None) -> np.ndarray:
        """The divergence the dipole sees: of the raw field or of its curl-free part, on the
        field's grid, or on ``dipole_grid`` (the field block-averaged, then decomposed on
        that coarser grid; ``decomposition``, the field's, is needed only on the field's
        grid)."""
        block = self._dipole_block
        raw = self.config.divergence_of == "raw"
        if block == (1, 1):
            return self._field_divergence(decomposition)
        u = block_mean(self._u, block, self._pooled[0])
        v = block_mean(self._v, block, self._pooled[1])
        if not raw:
            u, v = self._coarse_curl_free(u, v)
        dx, dy = block[1] * self._nhhd.dx, block[0] * self._nhhd.dy
        return divergence(u, v, dx, dy, self._coarse_div, self._coarse_work)

    def _field_divergence(self, decomposition: NHHDResult) -> np.ndarray:
        """The divergence of the raw field or of its curl-free part on the field's grid."""
        if self.config.divergence_of == "raw":
            return decomposition.div
        dx, dy = self._nhhd.dx, self._nhhd.dy
        d_u, d_v = decomposition.d_u, decomposition.d_v
        return divergence(d_u, d_v, dx, dy, self._div, self._work)

    # -- frames ------------------------------------------------------------------------------

    def _working_image(self, frame: np.ndarray, shape: tuple[int, ...] | None = None) -> np.ndarray:
        """BGR uint8 at the profile's resolution in the frame's own orientation. ``shape``:
        the (rows, cols) the frame must have (None: any). Changes no state."""
        if not isinstance(frame, np.ndarray) or frame.dtype != np.uint8:
            kind = getattr(frame, "dtype", type(frame).__name__)
            raise ValueError(f"tactile frame must be a uint8 image, got {kind}")
        if frame.ndim == 2:
            frame = cv2.cvtColor(frame, cv2.COLOR_GRAY2BGR)
        elif frame.ndim != 3 or frame.shape[2] not in (3, 4):
            raise ValueError(
                f"tactile frame must be H x W grey, BGR or BGRA, got shape {frame.shape}"
            )
        elif frame.shape[2] == 4:
            frame = cv2.cvtColor(frame, cv2.COLOR_BGRA2BGR)
        if shape is not None and frame.shape[:2] != shape:
            raise ValueError(
                f"frame of {frame.shape[1]} x {frame.shape[0]} px does not match the reference "
                f"({shape[1]} x {shape[0]} px); re-zero after changing size"
            )
        target = self._target_shape(frame.shape[0], frame.shape[1])
        if frame.shape[:2] == target:
            return frame
        return cv2.resize(frame, (target[1], target[0]), interpolation=cv2.INTER_AREA)

    def _target_shape(self, height: int, width: int) -> tuple[int, int]:
        p = self.profile
        for target in ((p.height_px, p.width_px), (p.width_px, p.height_px)):
            if (
                abs(height / width - target[0] / target[1])
                <= _ASPECT_TOLERANCE * target[0] / target[1]
            ):
                return target
        raise ValueError(
            f"frame of {width} x {height} px does not fit sensor profile '{p.name}' "
            f"({p.width_px} x {p.height_px} px in either orientation, or the same aspect ratio)"
        )

    # -- estimation --------------------------------------------------------------------------

    def push(self, frame: np.ndarray, t_s: float) -> WrenchEstimate:
        """Estimate the wrench from one frame captured at ``t_s`` seconds."""
        if self._open_left > 0:
            return self._capture_open(frame, t_s)
        if self._grid_flow is None and self._zeroing_left == 0:
            if self._awaiting_rezero:  # after capture_open: the caller calls rezero()
                return WrenchEstimate.zero(
                    t_s, zeroing=True, calibrated=self.calibration is not None
                )
            self.rezero()
        if self._zeroing_left > 0:
            return self._capture_reference(frame, t_s)
        image = self._working_image(frame, self._frame_shape)
        self._grid_flow.measure(image, self._grid_px)
        self._update_field()
        return self._estimate(t_s)

    def _capture_open(self, frame: np.ndarray, t_s: float) -> WrenchEstimate:
        first = self._open_count == 0
        image = self._working_image(frame, None if first else self._open_shape)
        total = image.astype(np.float32)
        if self._open_sum is not None:
            total += self._open_sum
        if first:
            self._open_shape = frame.shape[:2]
        if self._open_left == 1:
            self._open_image = np.clip(np.rint(total / (self._open_count + 1)), 0, 255).astype(
                np.uint8
            )
            total = None
        self._open_sum = total
        self._open_count += 1
        self._open_left -= 1
        return WrenchEstimate.zero(t_s, zeroing=True, calibrated=self.calibration is not None)

    def _capture_reference(self, frame: np.ndarray, t_s: float) -> WrenchEstimate:
        first = self._zeroing_count == 0
        image = self._working_image(frame, None if first else self._frame_shape)
        total = image.astype(np.float32)
        if self._reference_sum is not None:
            total += self._reference_sum
        if self._zeroing_left == 1:
            shape = frame.shape[:2] if first else self._frame_shape
            self._install_reference(total / (self._zeroing_count + 1), shape)
            total = None
        if first:
            self._frame_shape = frame.shape[:2]
        self._reference_sum = total
        self._zeroing_count += 1
        self._zeroing_left -= 1
        return WrenchEstimate.zero(t_s, zeroing=True, calibrated=self.calibration is not None)

    def _update_field(self) -> None:
        """Grid px -> mm in S, then the temporal EMA (alpha = weight of the newest field)."""
        scale = self.profile.mm_per_px
        alpha = self.config.ema_alpha
        if alpha >= 1.0 or not self._filtered:
            np.multiply(self._grid_px[..., 0], scale, out=self._u)
            np.multiply(self._grid_px[..., 1], scale, out=self._v)
            self._filtered = True
            return
        for component, target in ((0, self._u), (1, self._v)):
            target *= 1.0 - alpha
            np.multiply(self._grid_px[..., component], alpha * scale, out=self._work)
            target += self._work

    def _estimate(self, t_s: float) -> WrenchEstimate:
        decomposition = self._nhhd.decompose(self._u, self._v)
        if self._grasp_dipole.support is not None:
            dipole = self._grasp_dipole(self._field_divergence(decomposition))
        else:
            div = self._tilt_divergence(decomposition)
            if self._noise_gate is not None:
                gate = self._noise_gate(div)
                if gate < 1.0:  # not in place: the buffer may be the decomposition's
                    div = div * gate
            dipole = self._dipole(div)
        tau_x, tau_y = dipole.tilt_torque_raw
        fv_x, fv_y, fv_z = self._baseline(self._u, self._v)
        np.hypot(self._u, self._v, out=self._magnitude)
        contact = float(self._magnitude.mean()) > self.config.contact_threshold_mm
        slip = gross = recommended = False
        if self._slip is not None:
            status = self._slip.update(self._field_view, decomposition, t_s)
            self._last_slip = status
            slip, gross = status.incipient, status.gross
            recommended = self._rezero_policy.update(status, t_s)
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
            fv_tau_z=fv_z,
            contact=contact,
            degenerate=dipole.degenerate,
            slip_suspected=slip,
            slip_gross=gross,
            rezero_recommended=recommended,
            zeroing=False,
            calibrated=False,
        )
        if recommended and self.config.slip.rezero.auto:
            self.rezero()
        return self.calibration.apply(estimate) if self.calibration else estimate

    # -- inspection --------------------------------------------------------------------------

    @property
    def field(self) -> VectorField:
        """A copy of the latest (filtered) displacement field, mm in frame S."""
        if self._grid_flow is None:
            raise RuntimeError("no field yet: the estimator has no reference")
        return VectorField(self.x_mm, self.y_mm, self._u.copy(), self._v.copy())

    @property
    def last_slip_status(self) -> SlipStatus | None:
        """The slip detector's verdict on the latest frame (None: disabled or no frame yet)."""
        return self._last_slip

    @property
    def rezero_state(self) -> RezeroState:
        """The re-zero policy's current state."""
        return self._rezero_policy.state
