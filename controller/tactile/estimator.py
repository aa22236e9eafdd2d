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

import math
import numbers
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path

import cv2
import numpy as np

from controller.tactile.calibration import Calibration
from controller.tactile.dipole import GraspSupport, OriginRule
from controller.tactile.field import VectorField, grid_axes_mm
from controller.tactile.flow import GridFlow, make_grid_flow
from controller.tactile.frame_capture import FrameCapture, MeanImage
from controller.tactile.grid_lk import GridLKFlow
from controller.tactile.grid_pipeline import GridPipeline
from controller.tactile.noise_gate import NoiseGate
from controller.tactile.settings import (
    EstimatorConfig,
    FlowConfig,
    dipole_grid_mismatch,
    field_grid,
    sensor_estimator,
)
from controller.tactile.slip import RezeroPolicy, RezeroState, SlipStatus
from controller.tactile.wrench import WrenchEstimate
from core.sensor_profile import SensorProfile, sensor_profile

_ASPECT_TOLERANCE = 0.02
MAX_REFERENCE_FRAMES = 10_000
# Flow passes from the open gel to the grasp (each warm-started from the last): the grasp
# moves the gel by several px, more than one linearisation of grid_lk covers.
GRASP_FLOW_PASSES = 4

# The fallback dipole's divergence map (GridPipeline.divergence_map) per (configuration,
# scale, grid): a constant of those, shared by every estimator of the process (probing it
# takes 384 decompositions, about 20 ms, and each estimator would otherwise probe it again).
_DIVERGENCE_MAPS: dict[tuple, np.ndarray] = {}
_DIVERGENCE_MAPS_KEPT = 8

# Builds the flow from the reference to each pushed frame: (flow configuration, working
# image (H, W), grid rows, grid cols) -> GridFlow (px). The product's is ``make_grid_flow``.
GridFlowFactory = Callable[[FlowConfig, tuple[int, int], int, int], GridFlow]


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
    """Frame-to-wrench pipeline for one sensor (see module docstring); a ``WrenchSource``.
    ``config_name``: the configuration's name or YAML path, for reports
    (``estimator_for_sensor`` sets it; None for a configuration built in code).

    Hooks for experiments (the defaults are the product's):

    * ``flow``: builds the flow from the reference to each pushed frame (``GridFlowFactory``;
      e.g. the true field of a rendered sequence). The grasp's own field (the open gel
      against the reference) is always measured with the configuration's flow.
    * ``origin``: the tilt dipole's moment origin from the divergence it sees
      (``dipole.OriginRule``, mm in frame S), replacing the configuration's
      ``dipole_origin``; with it the grasp's support is not measured
      (``contact_centre_mm`` stays None)."""

    def __init__(
        self,
        config: EstimatorConfig,
        profile: SensorProfile,
        calibration: Calibration | None = None,
        config_name: str | None = None,
        *,
        flow: GridFlowFactory = make_grid_flow,
        origin: OriginRule | None = None,
    ) -> None:
        if calibration is not None and not isinstance(calibration, Calibration):
            raise TypeError(
                "calibration: expected a Calibration (e.g. Calibration.load(path)) or None, "
                f"got {type(calibration).__name__} {calibration!r}"
            )
        self.config = config
        self.profile = profile
        self.calibration = calibration
        self.config_name = config_name
        self._make_flow = flow
        self._origin = origin
        self._open = FrameCapture()  # the open gel
        self._given_support: GraspSupport | None = None  # set_contact_support's
        self._reference = FrameCapture()
        self._awaiting_rezero = False  # after capture_open, until rezero
        self._grid_flow: GridFlow | None = None
        self._pipeline: GridPipeline | None = None
        self._rezero_policy = RezeroPolicy(config.slip.rezero)
        self._last_slip: SlipStatus | None = None
        self._last_t_s = -math.inf  # the latest pushed frame's time (set_reference resets it)

    # -- reference ---------------------------------------------------------------------------

    @property
    def is_zeroed(self) -> bool:
        """True once a reference exists and is not being re-captured."""
        return self._grid_flow is not None and not self._reference.active

    def rezero(self, n_frames: int | None = None) -> None:
        """Capture a new reference from the next ``n_frames`` pushed frames (default: the
        configuration's ``reference_frames``). Call it after the grasp has settled.

        Raises ValueError, leaving the estimator as it was, unless ``n_frames`` is a whole
        number in [1, MAX_REFERENCE_FRAMES] (a bool, a float or NaN is refused)."""
        n = self._frame_count("rezero", n_frames)
        self._open.stop()
        self._awaiting_rezero = False
        self._reference.start(n)
        self._rezero_policy.reset()

    def capture_open(self, n_frames: int | None = None) -> None:
        """Capture the open gel (gripper open, nothing touching) from the next ``n_frames``
        pushed frames (default: ``reference_frames``); call ``rezero`` once the grasp has
        settled. The current reference is dropped: until the next reference exists, ``push``
        returns zero estimates flagged ``zeroing`` (it does not zero by itself on the
        closing gripper). Raises ValueError as ``rezero`` does."""
        n = self._frame_count("capture_open", n_frames)
        self._open.start(n)
        self._reference.stop()
        self._grid_flow = self._pipeline = None
        self._awaiting_rezero = True

    def set_open_reference(self, frames: np.ndarray | Sequence[np.ndarray] | None) -> None:
        """Use the mean of ``frames`` as the open gel (module docstring), None to forget it.
        Takes effect when the next reference is set (``rezero`` or ``set_reference``); the
        reference must then have the open frames' size. On a ValueError (as
        ``set_reference``) the estimator is left as it was."""
        if frames is None:
            self._open.result = None
            return
        self._open.set(self._mean_image(frames, "open"))

    def set_contact_support(self, support: GraspSupport | None) -> None:
        """Use ``support`` (weights on the field grid and their centre, mm in frame S) as the
        contact's support for the ``grasp_centroid`` dipole of every reference set from now on
        for which the open gel gives none (no open gel, or no contact against it); None to
        forget it. For a support found elsewhere, e.g. offline from a whole recording
        (controller/offline/recording_support.py). Unlike the open gel's, it does not stand
        for a contact seen: the no-contact gate stays. A support that does not fit the
        reference's grid makes ``set_reference`` raise ValueError."""
        self._given_support = support

    @property
    def contact_centre_mm(self) -> tuple[float, float] | None:
        """The contact's centre (x, y) in mm, frame S, measured from the grasp against the
        open gel when the reference was set, else the one given by ``set_contact_support``;
        None without either (or without contact)."""
        support = None if self._pipeline is None else self._pipeline.grasp_dipole.support
        return None if support is None else support.centre_mm

    def _frame_count(self, what: str, n_frames: int | None) -> int:
        n = self.config.reference_frames if n_frames is None else n_frames
        if (
            isinstance(n, bool)
            or not isinstance(n, numbers.Integral)
            or not 1 <= n <= MAX_REFERENCE_FRAMES
        ):
            raise ValueError(
                f"{what} needs a whole number of frames in [1, {MAX_REFERENCE_FRAMES}], got {n!r}"
            )
        return int(n)

    def set_reference(self, frames: np.ndarray | Sequence[np.ndarray]) -> None:
        """Use the mean of ``frames`` (one image, or a sequence / stack of images) now.

        Every frame is checked before anything changes: on a ValueError (no frame, a frame
        that is not an image, frames of different sizes, or of another size than the open
        gel's) the estimator is left as it was."""
        mean = self._mean_image(frames, "reference")
        self._install_reference(mean)
        self._last_t_s = -math.inf
        self._reference.set(mean)
        self._open.stop()
        self._awaiting_rezero = False

    def _mean_image(self, frames: np.ndarray | Sequence[np.ndarray], what: str) -> MeanImage:
        """The mean working image of ``frames`` and their (rows, cols)."""
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
        assert total is not None and shape is not None  # the stack is not empty
        return MeanImage.of_sum(total, len(stack), shape)

    def _install_reference(self, reference: MeanImage) -> None:
        """Build the flow and the pipeline on the reference first, then replace them: a
        ValueError leaves the estimator as it was."""
        open_gel = self._open.result
        shape = reference.frame_shape
        if open_gel is not None and open_gel.frame_shape != shape:
            raise ValueError(
                f"frame of {shape[1]} x {shape[0]} px does not match the open gel's frames "
                f"({open_gel.frame_shape[1]} x {open_gel.frame_shape[0]} px)"
            )
        image = reference.image
        height, width = image.shape[:2]
        rows, cols = field_grid(self.config, height, width)
        mismatch = dipole_grid_mismatch(self.config, rows, cols)
        if mismatch:
            raise ValueError(mismatch)
        grid_flow = self._make_flow(self.config.flow, (height, width), rows, cols)
        grid_flow.set_reference(image)
        x_mm, y_mm = grid_axes_mm(width, height, cols, rows, self.profile.mm_per_px)
        pipeline = GridPipeline(self.config, self.profile.mm_per_px, x_mm, y_mm, self._origin)
        support = None
        if open_gel is not None and self._measures_grasp:
            flow_config = replace(self.config.flow, warm_start=True)
            grasp_flow = make_grid_flow(flow_config, (height, width), rows, cols)
            grasp_flow.set_reference(open_gel.image)
            support = pipeline.grasp_support(grasp_flow, image, GRASP_FLOW_PASSES)
        given = support is None and self._measures_grasp and self._given_support is not None
        if given:
            support = self._given_support
        pipeline.grasp_dipole.set_grasp_support(support)
        if support is None or given:
            pipeline.noise_gate = self._noise_gate(grid_flow, pipeline)
        self._grid_flow = grid_flow
        self._pipeline = pipeline
        self._rezero_policy.reset()
        self._last_slip = None

    @property
    def _measures_grasp(self) -> bool:
        """Whether the tilt is taken about the grasp's support (``grasp_centroid``, no
        ``origin`` hook)."""
        return self._origin is None and self.config.dipole_origin == "grasp_centroid"

    def _noise_gate(self, grid_flow: GridFlow, pipeline: GridPipeline) -> NoiseGate | None:
        """The no-contact gate (controller/tactile/noise_gate.py) of the fallback dipole's
        divergence, from ``grid_flow``'s noise (None: no ``noise_gate`` configured)."""
        settings = self.config.noise_gate
        if settings is None or not isinstance(grid_flow, GridLKFlow):
            return None
        covariance = grid_flow.noise_covariance(settings.noise_grey, _divergence_map(pipeline))
        if not float(np.abs(covariance).max()) > 0.0:  # a featureless image: the field is 0
            return None
        return NoiseGate(covariance, settings.false_alarm)

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
        """Estimate the wrench from one frame captured at ``t_s`` seconds: a finite number,
        never before the previous frame's (TypeError, ValueError otherwise)."""
        t_s = self._frame_time(t_s)
        if self._open.active:
            self._open.add(self._working_image(frame, self._open.frame_shape), frame.shape[:2])
            return self._zeroing(t_s)
        if self._grid_flow is None and not self._reference.active:
            if self._awaiting_rezero:  # after capture_open: the caller calls rezero()
                return self._zeroing(t_s)
            self.rezero()
        if self._reference.active:
            image = self._working_image(frame, self._reference.frame_shape)
            self._reference.add(image, frame.shape[:2], self._install_reference)
            return self._zeroing(t_s)
        grid_flow, pipeline, reference = self._grid_flow, self._pipeline, self._reference.result
        assert grid_flow is not None and pipeline is not None and reference is not None  # zeroed
        image = self._working_image(frame, reference.frame_shape)
        grid_flow.measure(image, pipeline.grid_px)
        pipeline.update_field()
        estimate, slip = pipeline.estimate(t_s, self._rezero_policy)
        if slip is not None:
            self._last_slip = slip
        if estimate.rezero_recommended and self.config.slip.rezero.auto:
            self.rezero()
        return self.calibration.apply(estimate) if self.calibration else estimate

    def _frame_time(self, t_s: float) -> float:
        """``t_s`` as a float, checked against the previous frame's time (which it becomes)."""
        if isinstance(t_s, bool) or not isinstance(t_s, numbers.Real):
            raise TypeError(f"push: t_s: expected a number of seconds, got {t_s!r}")
        t = float(t_s)
        if not math.isfinite(t):
            raise ValueError(f"push: t_s: expected a finite time in seconds, got {t}")
        if t < self._last_t_s:
            raise ValueError(
                f"push: t_s: time went backwards, {t:g} s after a frame at {self._last_t_s:g} s"
            )
        self._last_t_s = t
        return t

    def _zeroing(self, t_s: float) -> WrenchEstimate:
        """The zero estimate of a frame taken into a capture."""
        return WrenchEstimate.zero(t_s, zeroing=True, calibrated=self.calibration is not None)

    # -- inspection --------------------------------------------------------------------------

    @property
    def field(self) -> VectorField:
        """A copy of the latest (filtered) displacement field, mm in frame S."""
        if self._pipeline is None:
            raise RuntimeError("no field yet: the estimator has no reference")
        return self._pipeline.field

    def field_divergence(self) -> np.ndarray:
        """The divergence of the latest field on the field grid, as the ``grasp_centroid``
        dipole sees it (``divergence_of``: of the curl-free part or the raw field),
        dimensionless, (rows, cols): a new array (an NHHD per call). RuntimeError without a
        reference."""
        if self._pipeline is None:
            raise RuntimeError("no field yet: the estimator has no reference")
        return self._pipeline.field_divergence()

    @property
    def noise_gated(self) -> bool:
        """True when the tilt passes the no-contact gate (``noise_gate``: a reference without
        the grasp's contact, measured by ``grid_lk`` on a textured image)."""
        return self._pipeline is not None and self._pipeline.noise_gate is not None

    @property
    def noise_gate_peak(self) -> float:
        """The largest statistic the no-contact gate has seen since the reference was set,
        relative to its threshold q (a noise-only field stays below about 1, a grasp's press
        is hundreds); 0 without a gate."""
        gate = None if self._pipeline is None else self._pipeline.noise_gate
        return 0.0 if gate is None else gate.peak

    @property
    def last_slip_status(self) -> SlipStatus | None:
        """The slip detector's verdict on the latest frame (None: disabled or no frame yet)."""
        return self._last_slip

    @property
    def rezero_state(self) -> RezeroState:
        """The re-zero policy's current state."""
        return self._rezero_policy.state


def _divergence_map(pipeline: GridPipeline) -> np.ndarray:
    """``pipeline.divergence_map()``, probed once per (configuration, scale, grid) in a
    process (read-only)."""
    key = (
        pipeline.config,
        pipeline.mm_per_px,
        tuple(pipeline.x_mm),
        tuple(pipeline.y_mm),
    )
    found = _DIVERGENCE_MAPS.get(key)
    if found is None:
        if len(_DIVERGENCE_MAPS) >= _DIVERGENCE_MAPS_KEPT:
            _DIVERGENCE_MAPS.clear()
        found = pipeline.divergence_map()
        found.flags.writeable = False
        _DIVERGENCE_MAPS[key] = found
    return found
