"""Estimator configuration (``configs/estimators/*.yaml``), as frozen validated dataclasses.

Declared and checked as every configuration is (core/config.py); every key is required in
a file, and ``null`` means "the library's default" where a field allows it.
"""

from __future__ import annotations

from typing import Literal

from core.config import (
    Config,
    ConfigError,
    config_dataclass,
    load_config,
    number,
    resolve_config_path,
)
from core.sensor_profile import SensorProfile

FlowMethod = Literal["dis", "farneback", "markers", "grid_lk"]


@config_dataclass
class DisParams(Config):
    """OpenCV DIS optical flow: a preset, then optional overrides of its tunables."""

    preset: Literal["ultrafast", "fast", "medium"]
    finest_scale: int | None = number(0, 10)
    patch_size: int | None = number(3, 64)
    patch_stride: int | None = number(1, 64)
    gradient_descent_iterations: int | None = number(1, 1000)
    variational_refinement_iterations: int | None = number(0, 100)
    variational_refinement_alpha: float | None = number(0, 1000)
    variational_refinement_delta: float | None = number(0, 1000)
    variational_refinement_gamma: float | None = number(0, 1000)
    use_mean_normalization: bool | None
    use_spatial_propagation: bool | None

    def __post_init__(self) -> None:
        if (
            self.patch_size is not None
            and self.patch_stride is not None
            and self.patch_stride > self.patch_size
        ):
            raise ValueError(
                f"key 'patch_stride': expected at most patch_size ({self.patch_size}), "
                f"got {self.patch_stride}"
            )


@config_dataclass
class FarnebackParams(Config):
    """OpenCV Farneback dense flow (cv2.calcOpticalFlowFarneback's arguments)."""

    pyr_scale: float = number(0.1, 0.9)
    levels: int = number(1, 10)
    winsize: int = number(3, 128)
    iterations: int = number(1, 50)
    poly_n: Literal[5, 7]
    poly_sigma: float = number(0.5, 3.0)
    gaussian_window: bool


@config_dataclass
class MarkerParams(Config):
    """Sparse tracking of the gel's printed markers with pyramidal Lucas-Kanade.

    Markers are found once in the reference (dark blobs against the smoothed background),
    tracked from the reference in every frame, and spread onto the grid by normalised
    Gaussian weights of width ``smoothing_cells`` grid cells.
    """

    detect_threshold: float = number(1, 255)
    min_area_px: int = number(1, 10000)
    max_area_px: int = number(1, 10000)
    window_px: int = number(5, 101)
    pyramid_levels: int = number(0, 6)
    max_iterations: int = number(1, 100)
    smoothing_cells: float = number(0.1, 5.0)
    min_markers: int = number(3, 100000)

    def __post_init__(self) -> None:
        if self.min_area_px > self.max_area_px:
            raise ValueError(
                f"key 'min_area_px': expected at most max_area_px ({self.max_area_px}), "
                f"got {self.min_area_px}"
            )
        if self.window_px % 2 == 0:
            raise ValueError(f"key 'window_px': expected an odd number, got {self.window_px}")


@config_dataclass
class GridLKParams(Config):
    """Regularised Lucas-Kanade on the grid (controller/tactile/grid_lk.py): one displacement
    per grid cell fitted to every pixel, with a membrane prior of relative weight
    ``smoothness``; images blurred by ``blur_sigma_px`` (px of the working image, 0: none);
    ``iterations`` Gauss-Newton steps; ``normalize_brightness``: a free brightness offset per
    cell and channel."""

    smoothness: float = number(0.0, 1000.0)
    blur_sigma_px: float = number(0.0, 10.0)
    iterations: int = number(1, 20)
    normalize_brightness: bool


@config_dataclass
class FlowConfig(Config):
    """How the displacement field is measured from images.

    ``color``: ``gray`` runs the flow once on the luminance; ``per_channel`` runs it on each
    colour channel and averages (the authors' choice). ``scale`` < 1 computes the flow on a
    downscaled image (vectors are scaled back). ``warm_start`` seeds each frame's dense flow
    with the previous one (faster convergence on large motion, but history-dependent).
    """

    method: FlowMethod
    color: Literal["gray", "per_channel"]
    scale: float = number(0.125, 1.0)
    warm_start: bool
    dis: DisParams
    farneback: FarnebackParams
    markers: MarkerParams
    grid_lk: GridLKParams


@config_dataclass
class RezeroConfig(Config):
    """When the zeroing reference should be refreshed after gross slip
    (controller/tactile/slip.py: ``RezeroPolicy``).

    After gross slip the policy waits until the tangential field (RMS, mm) has fallen to at
    most ``load_fraction`` of its peak during the slip (the load is released: back near the
    post-grasp level) and the whole field has changed by at most ``quiet_change_mm`` (largest
    cell, frame to frame) for ``quiet_s`` seconds; then it recommends a re-zero. ``auto``:
    the estimator applies the recommendation itself (captures a new reference).
    """

    auto: bool
    load_fraction: float = number(0.0, 1.0)
    quiet_change_mm: float = number(0.0, 1.0)
    quiet_s: float = number(0.0, 60.0)


@config_dataclass
class SlipConfig(Config):
    """The slip detector (controller/tactile/slip.py: ``SlipDetector``).

    It watches the divergence-free part of the zeroed field (rotational + harmonic NHHD
    parts, mm) and, each time that part has moved by ``min_increment_mm`` (largest cell)
    since the last evaluation, looks at the increment over the contact core: the cells where
    the tangential field is at least ``core_fraction`` of its largest value. Only loading
    increments count: their rigid motion must point within acos(``loading_cosine``) of the
    tangential field's own, and carry a tangential load: their rigid motion (mm, as
    ``CoreFit`` gives it) at least ``min_rigid_fraction`` of their RMS over the core. The
    residual of an affine fit to the increment (RMS over the core, relative to the
    increment's RMS) minus the grasp's stick baseline is the slip score. The baseline is
    the smallest residual of the first ``baseline_evaluations`` evaluations after zeroing,
    capped at ``baseline_max``; those evaluations only learn (score 0). A core of fewer than
    six cells is not judged.

    * incipient slip: score >= ``incipient_score``;
    * gross slip: score >= ``gross_score`` and then the tangential field (RMS) stops
      growing by more than ``growth_tolerance`` (relative) for ``gross_confirm_s`` seconds;
      it ends when that RMS falls below (1 - ``release_fraction``) of its peak.

    Below ``min_field_mm`` (largest cell of the tangential field) the contact counts as
    unloaded: no slip. ``enabled`` false: the detector does not run and the flags stay off.
    """

    enabled: bool
    min_field_mm: float = number(0.0, 10.0)
    min_increment_mm: float = number(1e-4, 10.0)
    core_fraction: float = number(0.0, 1.0)
    loading_cosine: float = number(-1.0, 1.0)
    min_rigid_fraction: float = number(0.0, 1.0)
    baseline_evaluations: int = number(1, 100)
    baseline_max: float = number(0.0, 1.0)
    incipient_score: float = number(0.0, 1.0)
    gross_score: float = number(0.0, 1.0)
    gross_confirm_s: float = number(0.0, 10.0)
    growth_tolerance: float = number(0.0, 1.0)
    release_fraction: float = number(0.0, 1.0)
    rezero: RezeroConfig

    def __post_init__(self) -> None:
        if self.gross_score < self.incipient_score:
            raise ValueError(
                f"key 'gross_score': expected at least incipient_score "
                f"({self.incipient_score}), got {self.gross_score}"
            )


@config_dataclass
class DipoleGrid(Config):
    """The grid the dipole works on: ``cols`` x ``rows`` cells over the whole image, each a
    block of the field's cells (so each must divide the field grid's count)."""

    cols: int = number(3, 64)
    rows: int = number(3, 64)


@config_dataclass
class NoiseGateConfig(Config):
    """The no-contact gate of the dipole without the grasp's contact
    (controller/tactile/noise_gate.py): ``noise_grey``, the camera's pixel noise (standard
    deviation per channel, grey levels); ``false_alarm``, the share of noise-only frames on
    which the gate starts to open."""

    noise_grey: float = number(0.01, 50.0)
    false_alarm: float = number(1e-12, 0.5)


@config_dataclass
class EstimatorConfig(Config):
    """The whole frame-to-wrench pipeline.

    ``stride_px``: grid cell size in working-image pixels (the grid has round(W/stride) x
    round(H/stride) cells; 26.667 gives the authors' 12 x 9 at 320 x 240).
    ``divergence_of``: the dipole uses the divergence of the raw field or of the NHHD
    curl-free part. ``dipole_grid``: the dipole works on the field block-averaged to
    this coarser grid (and decomposed again there for the curl-free part), while tau_z, the
    shear and the slip detector keep the full grid (null: the full grid itself). With square
    blocks this is exactly what an estimator with a proportionally larger stride computes.
    ``dipole_origin``: the point the dipole moment is taken about: the paper's centroid
    midpoint, moved smoothly toward the gel centre as one sign of divergence vanishes, or
    the gel centre (``sensor_centre``), or, weighted by the contact's support, its centre,
    both measured once per grasp from the closing press (``grasp_centroid``: needs the open
    gel's frames before the grasp reference, ``TactileEstimator.capture_open``; without them
    the centroid-midpoint rule on ``dipole_grid``; the grasp's own moment is always on the
    field grid, where its support localises it); ``dipole_full_midpoint_ratio``: the weak /
    strong mass ratio of the two signs from which on the midpoint is used unchanged
    (controller/tactile/dipole.py). ``tau_z_about``: the NHHD in-plane torque's origin, the
    gel centre or the rotational potential's extremum (controller/tactile/nhhd.py).
    ``ema_alpha``: weight of the newest field in the temporal filter (1 = off).
    ``reference_frames``: frames averaged into the reference by ``rezero()``.
    ``contact_threshold_mm``: mean displacement magnitude above which ``contact`` is set.
    ``slip``: the slip detector and the re-zero policy (``SlipConfig``).
    ``noise_gate``: without the grasp's contact, the tilt is zero until the field's
    divergence differs from camera noise (``NoiseGateConfig``; with ``grid_lk``, whose noise
    it propagates; other flows form no gate, as with null).
    """

    flow: FlowConfig
    stride_px: float = number(4, 160)
    divergence_of: Literal["raw", "curl_free"]
    dipole_origin: Literal["centroid_midpoint", "sensor_centre", "grasp_centroid"]
    dipole_full_midpoint_ratio: float = number(0.01, 1.0)
    tau_z_about: Literal["gel_centre", "rotation_centre"]
    dipole_grid: DipoleGrid | None
    ema_alpha: float = number(0.01, 1.0)
    reference_frames: int = number(1, 1000)
    contact_threshold_mm: float = number(0, 10)
    slip: SlipConfig
    noise_gate: NoiseGateConfig | None


def estimator_config(name_or_path: str) -> EstimatorConfig:
    """Load ``configs/estimators/NAME.yaml`` (or a YAML path)."""
    return load_config(EstimatorConfig, resolve_config_path(name_or_path, "estimators"))


def field_grid(config: EstimatorConfig, height_px: int, width_px: int) -> tuple[int, int]:
    """(rows, cols) of the estimator's field grid on a working image of that size."""
    rows = max(3, round(height_px / config.stride_px))
    cols = max(3, round(width_px / config.stride_px))
    return rows, cols


def dipole_grid_mismatch(config: EstimatorConfig, rows: int, cols: int) -> str | None:
    """Why ``config.dipole_grid`` cannot pool a field grid of ``rows`` x ``cols`` cells, or
    None if it can (each of its counts must divide the field grid's)."""
    grid = config.dipole_grid
    if grid is None or (rows % grid.rows == 0 and cols % grid.cols == 0):
        return None
    return (
        f"dipole_grid {grid.cols} x {grid.rows} must divide the estimator grid of "
        f"{cols} x {rows} cells (set by stride_px {config.stride_px:g})"
    )


def sensor_estimator(
    profile: SensorProfile, name_or_path: str | None = None
) -> tuple[str, EstimatorConfig]:
    """The configuration ``name_or_path``, or with None the sensor's own (its profile's
    ``estimator``), as (name, config). Marker tracking needs printed markers: asking for it
    on a sensor without (``marker_pitch_mm: null``) is a ConfigError, and so is a
    ``dipole_grid`` that does not divide the field grid at the sensor's resolution."""
    name = name_or_path or profile.estimator
    config = estimator_config(name)
    if config.flow.method == "markers" and profile.marker_pitch_mm is None:
        raise ConfigError(
            f"estimator '{name}' tracks printed markers, but sensor '{profile.name}' has none "
            "(marker_pitch_mm: null); choose a dense-flow estimator such as 'default'"
        )
    mismatch = dipole_grid_mismatch(
        config, *field_grid(config, profile.height_px, profile.width_px)
    )
    if mismatch:
        raise ConfigError(f"estimator '{name}' on sensor '{profile.name}': {mismatch}")
    return name, config
