"""GelSight Mini and DIGIT visuotactile cameras through OpenCV's V4L2 backend.

The camera is found by its persistent ``/dev/v4l/by-id`` name (see ``device_lookup``), opened
with ``cv2.VideoCapture(node, cv2.CAP_V4L2)`` and asked for MJPG, the configured size and rate,
and a driver queue of ``buffer_count`` buffers. When the V4L2 backend delivers MJPG we switch
``CAP_PROP_CONVERT_RGB`` off and decode the compressed buffer ourselves at reduced size (see
``decode``); any other capture (a video file, a YUYV stream) is decoded by OpenCV and only
cropped, resized and oriented.

Facts the defaults rest on:

* GelSight Mini: one mode only, MJPG 3280 x 2464 at 25 fps (``v4l2-ctl --list-formats-ext``
  in https://github.com/gelsightinc/gsrobotics/issues/36); gsrobotics crops 15 % off each
  border and resizes to 320 x 240 (``GelSightMini`` / ``crop_and_resize`` in ``utilities/``).
* DIGIT: digit-interface streams QVGA 320 x 240 at 60 fps by default (``DigitHandler.STREAMS``)
  and turns each frame with ``cv2.transpose`` then ``cv2.flip(frame, 0)``.

A grabber thread opens and configures the capture, then keeps only the newest frame and the
instant (on the injected clock) its grab returned; no camera call is made on the caller's
thread, so ``connect()`` takes at most ``connect_timeout_s`` (plus the by-id lookup) even
when opening the device hangs, and Ctrl-C interrupts it. ``read_latest(max_age_s)`` never
waits: it hands the newest frame over, or raises:

* DeviceNotConnectedError: not connected, or the camera was lost (its node disappeared, or
  ``max_read_failures`` grabs failed in a row);
* DeviceFaultError: the stream is frozen (``frozen_frame_count`` identical output images in a
  row), or ``max_read_failures`` frames in a row did not decode;
* DeviceTimeoutError: the newest frame is older than ``max_age_s`` (the stream stalled).

Compressed frames (``compress_frames(encode)``, for an episode): the grabber thread also
encodes each processed frame with ``encode``, as JPEG (``TactileFrame.jpeg``; the camera's
own MJPG buffer is the full 3280 x 2464 sensor image, not the cropped and resized frame the
estimator takes, so it is encoded again, off the control loop's thread).
``compressed(image)`` gives the JPEG of the frame ``read_latest`` handed over last.

A frame that does not decode (a cut or corrupted JPEG) is skipped, and the first of each run
of such frames is logged as a warning; the newest good frame stays available, with its own
grab time, so nothing downstream sees a wrong timestamp.
"""

from __future__ import annotations

import logging
import os
import threading
from collections.abc import Callable
from typing import Literal, Protocol

import cv2
import numpy as np

from core.clock import Clock, MonotonicClock
from core.config import Config, config_dataclass, number
from core.devices import ContextManagedDevice, TactileFrame
from core.errors import DeviceFaultError, DeviceNotConnectedError, DeviceTimeoutError
from drivers.tactile.decode import FrameProcessor, JpegDownscale, cropped_size
from drivers.tactile.device_lookup import find_capture_node

log = logging.getLogger(__name__)

MAX_V4L2_BUFFERS = 10  # MAX_V4L_BUFFERS in OpenCV's cap_v4l.cpp
_JOIN_TIMEOUT_S = 2.0


class Capture(Protocol):
    """The part of ``cv2.VideoCapture`` the driver uses."""

    def isOpened(self) -> bool: ...

    def set(self, prop_id: int, value: float) -> bool: ...

    def get(self, prop_id: int) -> float: ...

    def getBackendName(self) -> str: ...

    def grab(self) -> bool: ...

    def retrieve(self) -> tuple[bool, np.ndarray | None]: ...

    def release(self) -> None: ...


CaptureFactory = Callable[[str], Capture]


def open_v4l2(node: str) -> Capture:
    """The real transport: an OpenCV V4L2 capture on ``node`` (e.g. ``/dev/video2``)."""
    return cv2.VideoCapture(node, cv2.CAP_V4L2)


@config_dataclass
class TactileCameraConfig(Config):
    """Configuration of one tactile camera (see configs/sensors/*_camera.yaml).

    ``by_id_pattern``: fnmatch pattern for the camera's name in ``by_id_dir``; put the serial
    number in it when several sensors of one model are plugged in.
    ``width_px`` x ``height_px`` at ``frame_rate_hz``: the stream requested from the camera.
    ``output_width_px`` x ``output_height_px``: the size of the delivered image (after the
    DIGIT orientation, which swaps the axes).
    ``crop_border_fraction``: share of the full-resolution width and height cut off each border.
    ``jpeg_downscale``: decode MJPG frames at 1/1, 1/2, 1/4 or 1/8 of full size; the crop must
    still be at least as large as the output.
    ``buffer_count``: V4L2 driver buffers (1 = lowest latency).
    ``frozen_frame_count``: this many identical output images in a row is a frozen stream.
    ``max_read_failures``: this many failed grabs in a row means the camera is lost (this many
    undecodable frames in a row is a fault).
    ``connect_timeout_s``: how long ``connect()`` waits for the first frame.
    """

    model: Literal["gelsight_mini", "digit"]
    by_id_pattern: str
    width_px: int = number(16, 8192)
    height_px: int = number(16, 8192)
    frame_rate_hz: float = number(1, 1000)
    output_width_px: int = number(8, 8192)
    output_height_px: int = number(8, 8192)
    name: str = "tactile_camera"
    by_id_dir: str = "/dev/v4l/by-id"
    crop_border_fraction: float = number(0.0, 0.49, default=0.0)
    jpeg_downscale: JpegDownscale = 1
    buffer_count: int = number(1, MAX_V4L2_BUFFERS, default=1)
    frozen_frame_count: int = number(2, 100_000, default=25)
    max_read_failures: int = number(1, 10_000, default=5)
    connect_timeout_s: float = number(0.05, 60.0, default=3.0)

    def __post_init__(self) -> None:
        crop_w, crop_h = cropped_size(
            self.width_px, self.height_px, self.crop_border_fraction, self.jpeg_downscale
        )
        out_w, out_h = self.output_width_px, self.output_height_px
        if self.model == "digit":
            out_w, out_h = out_h, out_w  # resized before the DIGIT turn
        if crop_w < out_w or crop_h < out_h:
            raise ValueError(
                f"key 'jpeg_downscale': decoding {self.width_px}x{self.height_px} at "
                f"1/{self.jpeg_downscale} leaves {crop_w}x{crop_h} px after the crop, less than "
                f"the {out_w}x{out_h} output; use a smaller downscale"
            )

    def frame_processor(self) -> FrameProcessor:
        return FrameProcessor(
            output_width_px=self.output_width_px,
            output_height_px=self.output_height_px,
            crop_border_fraction=self.crop_border_fraction,
            jpeg_downscale=self.jpeg_downscale,
            digit_orientation=self.model == "digit",
        )


def _fourcc_text(value: float) -> str:
    code = int(value)
    return "".join(chr((code >> (8 * i)) & 0xFF) for i in range(4))


class _Grabber:
    """Opens the capture (``open_capture``) on its own thread, then owns it: grabs, processes,
    keeps the newest frame, releases."""

    def __init__(
        self,
        open_capture: Callable[[], Capture],
        node: str,
        config: TactileCameraConfig,
        processor: FrameProcessor,
        clock: Clock,
    ) -> None:
        self._open_capture = open_capture
        self._node = node
        self._config = config
        self._processor = processor
        self._clock = clock
        self._lock = threading.Lock()
        self._latest: TactileFrame | None = None
        self.encode: Callable[[np.ndarray], bytes] | None = None  # each frame's JPEG too
        self._fault: str | None = None
        self._lost: str | None = None
        self.open_error: DeviceNotConnectedError | None = None  # opening failed
        self.opened = threading.Event()  # set once the capture is open and configured
        self._stop = threading.Event()
        self._ready = threading.Event()  # set on the first frame and when the thread ends
        self._thread = threading.Thread(
            target=self._run, name=f"{config.name}-grabber", daemon=True
        )

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> bool:
        """Ask the thread to end and wait for it (not while the capture is still opening:
        the thread then releases it once open); False if it is still blocked in a camera
        call."""
        self._stop.set()
        if self.opened.is_set():
            self._thread.join(_JOIN_TIMEOUT_S)
        return not self._thread.is_alive()

    def wait_ready(self, timeout_s: float) -> None:
        self._ready.wait(timeout_s)

    @property
    def alive(self) -> bool:
        return self._thread.is_alive()

    def snapshot(self) -> tuple[TactileFrame | None, str | None, str | None]:
        """(newest frame, fault, loss), each None when there is none."""
        with self._lock:
            return self._latest, self._fault, self._lost

    def _run(self) -> None:
        capture: Capture | None = None
        try:
            capture = self._open_capture()
            self.opened.set()
            self._loop(capture)
        except DeviceNotConnectedError as exc:
            self.open_error = exc
        except Exception as exc:  # an OpenCV or programming error: report it, never hang
            log.exception("%s: grabber thread failed", self._config.name)
            with self._lock:
                self._lost = f"grabber thread failed: {exc!r}"
        finally:
            if capture is not None:
                capture.release()
            self._ready.set()

    def _lose(self, reason: str) -> None:
        with self._lock:
            self._lost = reason

    def _loop(self, capture: Capture) -> None:
        cfg_name = self._config.name
        limit = self._config.max_read_failures
        grab_failures = decode_failures = identical = 0
        previous: np.ndarray | None = None
        while not self._stop.is_set():
            if not capture.grab():
                if not os.path.exists(self._node):
                    self._lose(f"device node {self._node} is gone (unplugged?)")
                    return
                grab_failures += 1
                if grab_failures >= limit:
                    self._lose(f"{grab_failures} frame grabs in a row failed on {self._node}")
                    return
                continue
            t_s = self._clock.now()
            grab_failures = 0
            ok, raw = capture.retrieve()
            try:
                if not ok or raw is None:
                    raise ValueError("retrieve() returned no frame")
                image = self._processor(raw)
            except ValueError as exc:
                decode_failures += 1
                if decode_failures == 1:  # once per run of bad frames, not once per frame
                    log.warning("%s: a frame did not decode and was skipped: %s", cfg_name, exc)
                if decode_failures >= limit:
                    with self._lock:
                        self._fault = f"{decode_failures} frames in a row unusable: {exc}"
                continue
            decode_failures = 0
            repeated = previous is not None and np.array_equal(image, previous)
            identical = identical + 1 if repeated else 1
            previous = image
            image.flags.writeable = False
            fault = None
            if identical >= self._config.frozen_frame_count:
                fault = (
                    f"frozen stream: the last {identical} frames are identical "
                    "(camera firmware hung?); replug the sensor"
                )
            encode = self.encode
            jpeg = encode(image) if encode is not None else None
            with self._lock:
                self._latest = TactileFrame(t_s=t_s, image=image, jpeg=jpeg)
                self._fault = fault
            self._ready.set()


class TactileCamera(ContextManagedDevice):
    """A GelSight Mini or DIGIT camera (implements ``core.devices.TactileSensor``).

    ``capture_factory`` opens a capture on a device node; ``from_config`` uses ``open_v4l2``,
    tests pass captures on video files. ``clock`` stamps the frames and measures their age
    (``MonotonicClock`` when None). Images are uint8 H x W x 3 BGR, read-only; their x
    axis (columns) and y axis (rows) are the sensor frame S's in-plane axes.
    """

    def __init__(
        self,
        config: TactileCameraConfig,
        capture_factory: CaptureFactory,
        clock: Clock | None = None,
    ) -> None:
        self.config = config
        self.name = config.name
        self._capture_factory = capture_factory
        self._clock = clock if clock is not None else MonotonicClock()
        self._grabber: _Grabber | None = None
        self._encode: Callable[[np.ndarray], bytes] | None = None
        self._handed: TactileFrame | None = None  # the frame ``read_latest`` returned last

    @classmethod
    def from_config(
        cls,
        config: TactileCameraConfig,
        clock: Clock | None = None,
        capture_factory: CaptureFactory | None = None,
    ) -> TactileCamera:
        """The camera opened through ``capture_factory`` (V4L2 when None), not connected."""
        return cls(config, capture_factory if capture_factory is not None else open_v4l2, clock)

    @property
    def is_connected(self) -> bool:
        grabber = self._grabber
        return grabber is not None and grabber.alive and grabber.snapshot()[2] is None

    def connect(self) -> None:
        """Find, open and configure the camera, start grabbing, wait for the first frame.

        Raises DeviceNotConnectedError (no such device, cannot open it) or DeviceTimeoutError
        (opening hangs, or no frame within ``connect_timeout_s``).
        """
        if self.is_connected:
            return
        self.disconnect()  # clean up after a lost camera
        cfg = self.config
        node = find_capture_node(self.name, cfg.by_id_pattern, cfg.by_id_dir)
        grabber = _Grabber(lambda: self._open(node), node, cfg, cfg.frame_processor(), self._clock)
        grabber.encode = self._encode
        self._grabber = grabber
        try:
            grabber.start()
            grabber.wait_ready(cfg.connect_timeout_s)
        except BaseException:  # Ctrl-C: stop the grabber
            self.disconnect()
            raise
        frame, fault, lost = grabber.snapshot()
        if frame is None:
            self.disconnect()
            if grabber.open_error is not None:
                raise grabber.open_error
            if lost is not None:
                raise DeviceNotConnectedError(self.name, f"camera lost while starting: {lost}")
            if not grabber.opened.is_set():
                raise DeviceTimeoutError(
                    self.name,
                    f"opening {node} did not finish within {cfg.connect_timeout_s} s (key "
                    "'connect_timeout_s'): the camera or its driver hangs; replug the sensor",
                )
            detail = f" ({fault})" if fault else ""
            raise DeviceTimeoutError(
                self.name,
                f"opened {node} but got no usable frame within {cfg.connect_timeout_s} s{detail}; "
                "check the USB bandwidth (one camera per USB 2 controller) and the camera mode",
            )

    def _open(self, node: str) -> Capture:
        """Open and configure the capture (on the grabber's thread)."""
        capture = self._capture_factory(node)
        if not capture.isOpened():
            capture.release()
            raise DeviceNotConnectedError(
                self.name,
                f"cannot open {node}: check that you are in the 'video' group and that no "
                "other program uses the camera",
            )
        try:
            self._configure(capture, node)
        except BaseException:
            capture.release()
            raise
        return capture

    def _configure(self, capture: Capture, node: str) -> None:
        cfg = self.config
        capture.set(cv2.CAP_PROP_FOURCC, cv2.VideoWriter.fourcc(*"MJPG"))
        capture.set(cv2.CAP_PROP_FRAME_WIDTH, cfg.width_px)
        capture.set(cv2.CAP_PROP_FRAME_HEIGHT, cfg.height_px)
        capture.set(cv2.CAP_PROP_FPS, cfg.frame_rate_hz)
        capture.set(cv2.CAP_PROP_BUFFERSIZE, cfg.buffer_count)
        backend = capture.getBackendName()
        fourcc = _fourcc_text(capture.get(cv2.CAP_PROP_FOURCC))
        size = (
            int(capture.get(cv2.CAP_PROP_FRAME_WIDTH)),
            int(capture.get(cv2.CAP_PROP_FRAME_HEIGHT)),
        )
        # Only V4L2 hands over the compressed buffer with CONVERT_RGB off; FFmpeg would give
        # the luma plane instead.
        raw = backend == "V4L2" and fourcc == "MJPG" and capture.set(cv2.CAP_PROP_CONVERT_RGB, 0)
        log.info(
            "%s: opened %s with %s, %s %dx%d, %s",
            self.name,
            node,
            backend,
            fourcc,
            size[0],
            size[1],
            f"decoding MJPG at 1/{cfg.jpeg_downscale}" if raw else "decoded by OpenCV",
        )
        if backend == "V4L2" and size != (cfg.width_px, cfg.height_px):
            log.warning(
                "%s: asked for %dx%d, the camera streams %dx%d",
                self.name,
                cfg.width_px,
                cfg.height_px,
                size[0],
                size[1],
            )

    def disconnect(self) -> None:
        """Stop grabbing and release the camera; never raises, safe to call repeatedly."""
        grabber, self._grabber = self._grabber, None
        if grabber is not None and not grabber.stop():
            log.warning(
                "%s: grabber thread still blocked in the camera; it releases the camera "
                "when the call returns",
                self.name,
            )

    def read_latest(self, max_age_s: float) -> TactileFrame:
        """The newest frame, if it was grabbed at most ``max_age_s`` seconds ago."""
        if not max_age_s > 0:
            raise ValueError(f"max_age_s must be > 0, got {max_age_s!r}")
        grabber = self._grabber
        if grabber is None:
            raise DeviceNotConnectedError(self.name, "not connected: call connect() first")
        frame, fault, lost = grabber.snapshot()
        if lost is not None:
            raise DeviceNotConnectedError(
                self.name, f"camera lost: {lost}; check the cable, then connect() again"
            )
        if fault is not None:
            raise DeviceFaultError(self.name, fault)
        if frame is None:
            raise DeviceTimeoutError(self.name, "no frame received yet")
        age_s = self._clock.now() - frame.t_s
        if age_s > max_age_s:
            raise DeviceTimeoutError(
                self.name,
                f"newest frame is {age_s * 1e3:.0f} ms old (max {max_age_s * 1e3:.0f} ms): "
                "the stream stalled",
            )
        self._handed = frame
        return frame

    def compress_frames(self, encode: Callable[[np.ndarray], bytes] | None) -> None:
        """Give each frame grabbed from now on ``encode(image)`` too, its JPEG, encoded on the
        grabber thread; None: no more (see the module docstring)."""
        self._encode = encode
        if self._grabber is not None:
            self._grabber.encode = encode

    def compressed(self, image: np.ndarray) -> bytes | None:
        """The JPEG of ``image`` if it is the image of the frame ``read_latest`` returned last
        (the same object) and that frame was compressed, else None."""
        handed = self._handed
        return handed.jpeg if handed is not None and handed.image is image else None
