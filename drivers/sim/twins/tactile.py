"""Simulated twin of a GelSight Mini / DIGIT camera (implements ``core.devices.TactileSensor``).

Frames. The twin "captures" frame ``k`` at ``t_k = t_connect + k / frame_rate_hz`` on the
injected clock (``core.clock``). A frame is the marker gel of
``drivers.sim.render.gel_renderer.GelRenderer`` at the configured output size, warped by the
forward displacement field that the **field source** gives for ``t_k`` (px, (h, w, 2) at any
grid resolution with the image's aspect, e.g. the output size or a coarse physics grid; see
drivers/sim/render/field_grid.py), plus Gaussian pixel noise of ``noise_grey`` grey levels, as uint8
BGR (read-only, as the real driver delivers them).

A field source is any callable ``source(t_s) -> field or None`` (``None``: no contact, the
reference image). Set it with ``set_field_source``; the default is no contact. This is where
a contact model plugs in (the gel physics simulator of a later issue).

Timing (``SensorTiming``; all zero by default): frame ``k`` is captured at ``t_k`` moved by
a seeded uniform draw within +-``jitter_s`` and arrives ``latency_s`` later; a frame is
stamped with its arrival time, as the real driver stamps a frame when it reads it, and
shows the gel at its capture time. The stream starts ``latency_s`` before ``connect()``
(the camera was already capturing), so frame 0 arrives at the connection. With a
``drift_period_s``, the lighting drift level of a frame is the time since the connection
over that period (the renderer's ``drift``).

Compressed frames (``compress_frames(encode)``, for an episode): each frame rendered from
then on also carries ``encode(image)``, its JPEG (``TactileFrame.jpeg``), encoded once when the
frame is rendered, on the thread that reads it (the loop's); the image the estimator takes is
unchanged. ``compressed(image)`` gives the JPEG of the newest frame handed over.

``read_latest(max_age_s)`` has the real driver's semantics: the newest frame captured at or
before ``now()``, or DeviceTimeoutError when it is older than ``max_age_s`` (e.g. after
``stall()``); DeviceNotConnectedError before ``connect()`` and after ``unplug()`` ("camera
lost"); repeated reads of one frame return the same object.

Randomness (marker jitter, gel texture, pixel noise) comes from the injected ``rng``; the
noise of frame ``k`` depends only on (``rng``'s draws at construction, ``k``), so a frame
does not depend on which earlier frames were read (drivers/sim/render/noise_bank.py).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from core.clock import Clock, MonotonicClock
from core.config import Config, config_dataclass, number
from core.devices import ContextManagedDevice, TactileFrame
from core.errors import DeviceNotConnectedError, DeviceTimeoutError
from core.sensor_profile import sensor_profile
from drivers.sim.render.gel_renderer import GelRenderer
from drivers.sim.render.image_effects import ImageEffects
from drivers.tactile.camera import TactileCameraConfig

FieldSource = Callable[[float], np.ndarray | None]
"""Gives the forward displacement field (h, w, 2) in px at a time in s, or None."""

_JITTER_BANK = 4096  # frame k's capture jitter is draw k mod this of one seeded bank


@dataclass(frozen=True)
class SensorTiming:
    """When frames are captured and arrive, and the lighting's drift (see the module
    docstring): ``latency_s`` from capture to arrival, ``jitter_s`` the capture time's
    uniform spread (less than half a frame period), ``drift_period_s`` the time per drift
    level (``None``: no drift)."""

    latency_s: float = 0.0
    jitter_s: float = 0.0
    drift_period_s: float | None = None


@config_dataclass
class SimTactileSettings(Config):
    """The ``sim:`` section of a tactile camera YAML.

    ``noise_grey``: standard deviation of the pixel noise, grey levels. ``seed``: seed of the
    twin's randomness when the registry builds it. ``marker_radius_px``: radius of the
    printed markers in the output image, px; ``None`` for a gel without markers (DIGIT).
    The markers' pitch is the sensor profile's (see ``SimTactileConfig``).
    """

    noise_grey: float = number(0.0, 50.0)
    seed: int = number(0, 2**32 - 1)
    marker_radius_px: float | None = number(0.5, 100.0)


@config_dataclass(kw_only=True)
class SimTactileConfig(TactileCameraConfig):
    """A tactile camera YAML with ``backend: sim``: the real driver's keys (output size, frame
    rate, name) plus the ``sim:`` section.

    ``marker_pitch_px`` is not a key: the twin prints its markers at the pitch of the sensor
    profile of its ``model`` (configs/sensors/MODEL.yaml, ``SensorProfile.marker_pitch_px``),
    the one source of the sensor's geometry; ``None`` for a sensor without markers.
    """

    sim: SimTactileSettings
    marker_pitch_px: float | None = field(init=False)

    def __post_init__(self) -> None:
        super().__post_init__()
        pitch_px = sensor_profile(self.model).marker_pitch_px
        object.__setattr__(self, "marker_pitch_px", pitch_px)
        radius_px = self.sim.marker_radius_px
        if (pitch_px is None) != (radius_px is None):
            raise ValueError(
                "key 'sim.marker_radius_px': expected null for a sensor without printed "
                f"markers and a number for one with them; sensor '{self.model}' has "
                f"{'none' if pitch_px is None else 'markers'}, got {radius_px!r}"
            )
        if pitch_px is not None and radius_px is not None and radius_px > pitch_px / 2:
            raise ValueError(
                f"key 'sim.marker_radius_px': expected at most half the marker pitch "
                f"({pitch_px / 2:.3g} px), got {radius_px!r}"
            )


class SimTactileSensor(ContextManagedDevice):
    """The tactile camera twin; see the module docstring. ``clock`` defaults to real time,
    ``rng`` to ``numpy.random.default_rng(config.sim.seed)``; ``appearance`` names the
    gel's look (drivers/sim/render/appearance.py; the speckle gel by default)."""

    def __init__(
        self,
        config: SimTactileConfig,
        clock: Clock | None = None,
        rng: np.random.Generator | None = None,
        field_source: FieldSource | None = None,
        appearance: str = "speckle",
        effects: ImageEffects | None = None,
        timing: SensorTiming = SensorTiming(),
    ) -> None:
        self.config = config
        self.name = config.name
        self._clock = clock if clock is not None else MonotonicClock()
        rng = rng if rng is not None else np.random.default_rng(config.sim.seed)
        sim = config.sim
        period_s = 1.0 / config.frame_rate_hz
        if not 0.0 <= timing.jitter_s < period_s / 2 or timing.latency_s < 0.0:
            raise ValueError(
                f"timing: expected a latency >= 0 and a jitter below half the frame period "
                f"({period_s / 2} s), got {timing!r}"
            )
        self._renderer = GelRenderer(
            width_px=config.output_width_px,
            height_px=config.output_height_px,
            pitch_px=config.marker_pitch_px,
            dot_radius_px=sim.marker_radius_px or 0.0,
            effects=effects if effects is not None else ImageEffects(noise_grey=sim.noise_grey),
            rng=rng,
            appearance=appearance,
        )
        self._timing = timing
        self._jitter_s = (
            rng.uniform(-timing.jitter_s, timing.jitter_s, _JITTER_BANK)
            if timing.jitter_s > 0
            else np.zeros(1)
        )
        self._source = field_source
        self._present = True
        self._connected = False
        self._lost = False
        self._t0_s = 0.0  # time of frame 0
        self._stalled_after: int | None = None  # last frame index before a stall
        self._latest: tuple[int, TactileFrame] | None = None
        self._encode: Callable[[np.ndarray], bytes] | None = None

    @classmethod
    def from_config(
        cls, config: SimTactileConfig, clock: Clock | None = None, capture_factory: Any = None
    ) -> SimTactileSensor:
        """The twin on ``clock`` (real time when None), seeded by ``config.sim.seed``;
        ``capture_factory`` is accepted for the same call as ``TactileCamera.from_config``
        and ignored."""
        return cls(config, clock)

    @property
    def shape_hw(self) -> tuple[int, int]:
        """Image height and width, px: a field source gives (h, w, 2) with this aspect."""
        return (self.config.output_height_px, self.config.output_width_px)

    def set_field_source(self, source: FieldSource | None) -> None:
        """Use ``source(t_s)`` for the displacement field of frames captured from now on."""
        self._source = source

    # -- lifecycle ---------------------------------------------------------------------

    @property
    def is_connected(self) -> bool:
        return self._connected and not self._lost

    def connect(self) -> None:
        """Start streaming; the first frame is captured now."""
        if self.is_connected:
            return
        if not self._present:
            raise DeviceNotConnectedError(
                self.name,
                f"no capture node ('-index0') in {self.config.by_id_dir} matches "
                f"{self.config.by_id_pattern!r}: the simulated camera is unplugged",
            )
        self._connected, self._lost = True, False
        self._t0_s = self._clock.now() - self._timing.latency_s
        self._stalled_after = None
        self._latest = None

    def disconnect(self) -> None:
        self._connected = False
        self._latest = None

    # -- reading -----------------------------------------------------------------------

    def read_latest(self, max_age_s: float) -> TactileFrame:
        """The newest frame, if it was captured at most ``max_age_s`` seconds ago."""
        if not max_age_s > 0:
            raise ValueError(f"max_age_s must be > 0, got {max_age_s!r}")
        if not self._connected:
            raise DeviceNotConnectedError(self.name, "not connected: call connect() first")
        if self._lost:
            raise DeviceNotConnectedError(
                self.name,
                "camera lost: the simulated camera was unplugged; check the cable, then "
                "connect() again",
            )
        now = self._clock.now()
        index = self._frame_index(now)
        if self._stalled_after is not None:
            index = min(index, self._stalled_after)
        t_s = self._frame_time(index)
        age_s = now - t_s
        if age_s > max_age_s:
            raise DeviceTimeoutError(
                self.name,
                f"newest frame is {age_s * 1e3:.0f} ms old (max {max_age_s * 1e3:.0f} ms): "
                "the stream stalled",
            )
        if self._latest is None or self._latest[0] != index:
            image = self._render(index, self._capture_time(index))
            jpeg = self._encode(image) if self._encode is not None else None
            self._latest = (index, TactileFrame(t_s=t_s, image=image, jpeg=jpeg))
        return self._latest[1]

    def compress_frames(self, encode: Callable[[np.ndarray], bytes] | None) -> None:
        """Give each frame rendered from now on ``encode(image)`` too, its JPEG; None: no
        more (see the module docstring)."""
        self._encode = encode

    def compressed(self, image: np.ndarray) -> bytes | None:
        """The JPEG of ``image`` if it is the newest frame's image (the same object) and that
        frame was compressed, else None."""
        latest = self._latest
        return latest[1].jpeg if latest is not None and latest[1].image is image else None

    # -- simulation hooks --------------------------------------------------------------

    def stall(self) -> None:
        """Stop capturing new frames (the newest one ages), as a hung stream does."""
        if self._stalled_after is None:
            self._stalled_after = self._frame_index(self._clock.now())

    def resume(self) -> None:
        """Capture again after ``stall()``: the next frame is captured now."""
        if self._stalled_after is None:
            return
        next_index = self._stalled_after + 1
        self._t0_s = self._clock.now() - next_index / self.config.frame_rate_hz
        self._t0_s -= self._timing.latency_s
        self._stalled_after = None

    def unplug(self) -> None:
        """Pull the cable: reads raise "camera lost" and ``connect()`` fails until ``plug()``."""
        self._present = False
        self._lost = self._connected

    def plug(self) -> None:
        """Plug the camera back in (call ``connect()`` again to stream)."""
        self._present = True

    # -- internals ---------------------------------------------------------------------

    def _frame_index(self, now: float) -> int:
        """The newest frame that has arrived by ``now`` (0 at the latest)."""
        rate = self.config.frame_rate_hz
        capture_s = now - self._timing.latency_s
        index = math.floor((capture_s - self._t0_s + self._timing.jitter_s) * rate + 1e-9)
        while index > 0 and self._capture_time(index) > capture_s + 1e-12:
            index -= 1
        return max(0, index)

    def _capture_time(self, index: int) -> float:
        jitter = self._jitter_s[index % len(self._jitter_s)] if index > 0 else 0.0
        return self._t0_s + index / self.config.frame_rate_hz + float(jitter)

    def _frame_time(self, index: int) -> float:
        """Frame ``index``'s arrival time: its stamp."""
        return self._capture_time(index) + self._timing.latency_s

    def _render(self, index: int, t_s: float) -> np.ndarray:
        field = self._source(t_s) if self._source is not None else None
        period = self._timing.drift_period_s
        drift = 0.0
        if period is not None:  # the time since the connection, in drift levels
            drift = max(0.0, t_s - self._t0_s - self._timing.latency_s) / period
        try:
            frame = self._renderer.render(field, frame_index=index, drift=drift)
        except ValueError as exc:
            raise ValueError(f"field source: {exc}") from exc
        frame.flags.writeable = False
        return frame
