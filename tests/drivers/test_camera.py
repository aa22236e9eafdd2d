"""Tactile camera driver against real OpenCV captures on MJPG video files.

The peer is OpenCV's FFmpeg backend reading an MJPG .avi written by cv2.VideoWriter, either
decoded (BGR images, like any capture) or in raw mode (``CAP_PROP_FORMAT = -1``), which hands
over each compressed JPEG as a ``1 x N`` uint8 array, the layout V4L2 gives with
``CAP_PROP_CONVERT_RGB = 0``. ``PacedCapture`` only adds a camera's timing around it: grabs
come at a fixed rate and can be paused (a stalled camera).
"""

from __future__ import annotations

import os
import threading
import time
from collections.abc import Callable
from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml

from core.clock import ManualClock
from core.devices import TactileFrame, TactileSensor
from core.errors import DeviceFaultError, DeviceNotConnectedError, DeviceTimeoutError
from drivers.registry import load_device, load_device_config
from drivers.tactile import TactileCamera, TactileCameraConfig
from drivers.tactile.decode import (
    FrameProcessor,
    crop_borders,
    decode_jpeg,
    is_jpeg_buffer,
    orient_like_digit_sdk,
)
from drivers.tactile.device_lookup import find_capture_node

REPO = Path(__file__).resolve().parents[2]
MINI_ID = "usb-Arducam_Technology_Co.__Ltd._GelSight_Mini_R0B_28F5-K4RR_28F5K4RR-video-index"
DIGIT_ID = "usb-Meta_DIGIT_D20001-video-index"


class PacedCapture:
    """A real OpenCV capture delivering frames at ``rate_hz``, pausable, optionally looping
    (reopened at the end of the file), like a camera that streams until unplugged."""

    def __init__(
        self, open_inner: Callable[[], cv2.VideoCapture], rate_hz: float, loop: bool
    ) -> None:
        self._open_inner = open_inner
        self._inner = open_inner()
        self._period_s = 1.0 / rate_hz
        self._loop = loop
        self._next_s = time.monotonic()
        self._running = threading.Event()
        self._running.set()

    def pause(self) -> None:
        self._running.clear()

    def resume(self) -> None:
        self._running.set()

    def isOpened(self) -> bool:
        return self._inner.isOpened()

    def set(self, prop_id: int, value: float) -> bool:
        return self._inner.set(prop_id, value)

    def get(self, prop_id: int) -> float:
        return self._inner.get(prop_id)

    def getBackendName(self) -> str:
        return self._inner.getBackendName()

    def grab(self) -> bool:
        if not self._running.wait(timeout=5.0):
            return False
        self._next_s = max(self._next_s + self._period_s, time.monotonic())
        time.sleep(max(0.0, self._next_s - time.monotonic()))
        if self._inner.grab():
            return True
        if not self._loop:
            return False
        self._inner.release()
        self._inner = self._open_inner()
        return self._inner.grab()

    def retrieve(self) -> tuple[bool, np.ndarray | None]:
        return self._inner.retrieve()

    def release(self) -> None:
        self._inner.release()


def write_avi(path: Path, frames: list[np.ndarray], quality: int = 95) -> Path:
    h, w = frames[0].shape[:2]
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"MJPG"), 30, (w, h))
    assert writer.isOpened()
    writer.set(cv2.VIDEOWRITER_PROP_QUALITY, quality)
    for frame in frames:
        writer.write(frame)
    writer.release()
    return path


def textured(h: int, w: int, seed: int) -> np.ndarray:
    """A smooth random image (JPEG-friendly, no two seeds alike)."""
    rng = np.random.default_rng(seed)
    small = rng.integers(30, 220, (max(2, h // 16), max(2, w // 16), 3), dtype=np.uint8)
    return cv2.resize(small, (w, h), interpolation=cv2.INTER_CUBIC)


def by_id_dir(tmp_path: Path, id_prefix: str, target: Path) -> Path:
    """A by-id directory: the capture node (-index0) and metadata node (-index1) of the camera,
    and another camera, as symlinks; the capture node points at ``target``."""
    d = tmp_path / "by-id"
    d.mkdir(parents=True)
    meta = tmp_path / "metadata-node"
    meta.write_bytes(b"")
    other = tmp_path / "other-node"
    other.write_bytes(b"")
    (d / f"{id_prefix}0").symlink_to(target)
    (d / f"{id_prefix}1").symlink_to(meta)
    (d / "usb-046d_HD_Pro_Webcam_C920_ABCD1234-video-index0").symlink_to(other)
    return d


def mini_config(directory: Path, **overrides: object) -> TactileCameraConfig:
    fields: dict[str, object] = dict(
        model="gelsight_mini",
        by_id_pattern="usb-Arducam_Technology_Co.__Ltd._GelSight_Mini_*",
        by_id_dir=str(directory),
        width_px=3280,
        height_px=2464,
        frame_rate_hz=25,
        output_width_px=320,
        output_height_px=240,
        crop_border_fraction=0.15,
        jpeg_downscale=4,
        connect_timeout_s=2.0,
    )
    fields.update(overrides)
    return TactileCameraConfig(**fields)  # type: ignore[arg-type]


def digit_config(directory: Path, **overrides: object) -> TactileCameraConfig:
    fields: dict[str, object] = dict(
        model="digit",
        by_id_pattern="usb-*_DIGIT_*",
        by_id_dir=str(directory),
        width_px=320,
        height_px=240,
        frame_rate_hz=60,
        output_width_px=240,
        output_height_px=320,
        connect_timeout_s=2.0,
    )
    fields.update(overrides)
    return TactileCameraConfig(**fields)  # type: ignore[arg-type]


def paced_factory(
    raw: bool, rate_hz: float = 100.0, loop: bool = True
) -> tuple[Callable[[str], PacedCapture], list[PacedCapture]]:
    """A capture factory over the FFmpeg backend; returns it and the captures it made."""
    made: list[PacedCapture] = []
    params = [cv2.CAP_PROP_FORMAT, -1] if raw else []

    def factory(node: str) -> PacedCapture:
        cap = PacedCapture(lambda: cv2.VideoCapture(node, cv2.CAP_FFMPEG, params), rate_hz, loop)
        made.append(cap)
        return cap

    return factory, made


def wait_for(condition: Callable[[], bool], timeout_s: float = 3.0) -> None:
    deadline = time.monotonic() + timeout_s
    while not condition():
        assert time.monotonic() < deadline, "condition not met in time"
        time.sleep(0.01)


def raises_now(camera: TactileCamera, error: type[Exception], max_age_s: float = 1.0) -> bool:
    try:
        camera.read_latest(max_age_s)
    except error:
        return True
    return False


def blob_centroid(image: np.ndarray, background: int) -> tuple[float, float]:
    """(row, col) centroid of the pixels brighter than ``background``."""
    weight = np.clip(image.astype(float).mean(axis=2) - background - 10, 0, None)
    rows, cols = np.indices(weight.shape)
    return float((rows * weight).sum() / weight.sum()), float((cols * weight).sum() / weight.sum())


# --- by-id lookup -------------------------------------------------------------------------


def test_lookup_takes_the_capture_node_not_the_metadata_node(tmp_path: Path) -> None:
    target = tmp_path / "video2"
    target.write_bytes(b"")
    d = by_id_dir(tmp_path, MINI_ID, target)
    assert find_capture_node("gsmini", "*GelSight_Mini*", str(d)) == str(target)


def test_lookup_wrong_pattern_lists_what_was_found(tmp_path: Path) -> None:
    target = tmp_path / "video2"
    target.write_bytes(b"")
    d = by_id_dir(tmp_path, MINI_ID, target)
    with pytest.raises(DeviceNotConnectedError) as info:
        find_capture_node("gsmini", "usb-*_DIGIT_*", str(d))
    assert info.value.device == "gsmini"
    assert f"{MINI_ID}0" in info.value.message and "C920" in info.value.message


def test_lookup_refuses_two_matching_cameras(tmp_path: Path) -> None:
    target = tmp_path / "video2"
    target.write_bytes(b"")
    d = by_id_dir(tmp_path, MINI_ID, target)
    second_mini = "usb-Arducam_Technology_Co.__Ltd._GelSight_Mini_R0B_2BNN-4ZE7_2BNN4ZE7"
    (d / f"{second_mini}-video-index0").symlink_to(target)
    with pytest.raises(DeviceNotConnectedError, match="matches 2 capture nodes"):
        find_capture_node("gsmini", "*GelSight_Mini*", str(d))


def test_lookup_missing_directory_and_dangling_link(tmp_path: Path) -> None:
    with pytest.raises(DeviceNotConnectedError, match="does not exist"):
        find_capture_node("gsmini", "*", str(tmp_path / "nowhere"))
    d = by_id_dir(tmp_path, MINI_ID, tmp_path / "unplugged")
    with pytest.raises(DeviceNotConnectedError, match="which does not exist"):
        find_capture_node("gsmini", "*GelSight_Mini*", str(d))


# --- configuration ------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("override", "key"),
    [
        ({"model": "gelsight_r1"}, "model"),
        ({"by_id_pattern": ""}, "by_id_pattern"),
        ({"width_px": 3280.0}, "width_px"),
        ({"frame_rate_hz": 0}, "frame_rate_hz"),
        ({"crop_border_fraction": 0.5}, "crop_border_fraction"),
        ({"jpeg_downscale": 3}, "jpeg_downscale"),
        ({"jpeg_downscale": 8}, "jpeg_downscale"),  # 287x216 after the crop < 320x240
        ({"buffer_count": 0}, "buffer_count"),
        ({"frozen_frame_count": 1}, "frozen_frame_count"),
        ({"max_read_failures": True}, "max_read_failures"),
        ({"connect_timeout_s": -1.0}, "connect_timeout_s"),
    ],
)
def test_config_errors_name_the_key(tmp_path: Path, override: dict, key: str) -> None:
    with pytest.raises(ValueError, match=f"key '{key}'"):
        mini_config(tmp_path, **override)


def test_digit_output_size_is_checked_after_the_turn(tmp_path: Path) -> None:
    digit_config(tmp_path)  # 320x240 stream -> 240x320 image
    with pytest.raises(ValueError, match="jpeg_downscale"):
        digit_config(tmp_path, jpeg_downscale=2)


@pytest.mark.parametrize("name", ["gelsight_mini_camera.yaml", "digit_camera.yaml"])
def test_example_configs_load(name: str) -> None:
    config = load_device_config(REPO / "configs" / "sensors" / name, backend="real").config
    assert type(config) is TactileCameraConfig
    assert config.by_id_dir == "/dev/v4l/by-id"


# --- decoding and geometry ------------------------------------------------------------------


def test_jpeg_buffer_decodes_at_reduced_size() -> None:
    image = textured(2464, 3280, seed=1)
    ok, jpeg = cv2.imencode(".jpg", image)
    assert ok and is_jpeg_buffer(jpeg.reshape(1, -1)) and is_jpeg_buffer(jpeg.ravel())
    assert not is_jpeg_buffer(image)
    for downscale, shape in [
        (1, (2464, 3280)),
        (2, (1232, 1640)),
        (4, (616, 820)),
        (8, (308, 410)),
    ]:
        assert decode_jpeg(jpeg, downscale).shape == (*shape, 3)
    ok, odd = cv2.imencode(".jpg", textured(241, 321, seed=2))
    assert decode_jpeg(odd, 4).shape == (61, 81, 3)  # ceil, as libjpeg scales


def test_undecodable_frames_are_value_errors() -> None:
    ok, jpeg = cv2.imencode(".jpg", textured(240, 320, seed=3))
    processor = FrameProcessor(output_width_px=320, output_height_px=240)
    garbage = np.frombuffer(b"\xff\xd8" + bytes(range(256)) * 4, np.uint8).reshape(1, -1)
    with pytest.raises(ValueError, match="decode failed"):
        processor(garbage)
    with pytest.raises(ValueError, match="unexpected frame layout"):
        processor(np.zeros((240, 320), np.uint8))
    with pytest.raises(ValueError, match="downscale"):
        decode_jpeg(jpeg, 3)


def test_mini_crop_removes_exactly_15_percent_of_each_border() -> None:
    image = np.zeros((2464, 3280, 3), np.uint8)
    image[:, :] = (0, 0, 255)  # red border
    image[369 : 2464 - 369, 492 : 3280 - 492] = (0, 255, 0)  # int(2464*.15), int(3280*.15)
    processor = FrameProcessor(320, 240, crop_border_fraction=0.15)
    out = processor(image)
    assert out.shape == (240, 320, 3) and out.dtype == np.uint8
    assert np.all(out == (0, 255, 0))


@pytest.mark.parametrize("downscale", [1, 2, 4])
def test_mini_geometry_full_and_reduced_decode(downscale: int) -> None:
    image = np.full((2464, 3280, 3), 60, np.uint8)
    y0, x0 = 900, 2500  # full-resolution centre of a bright marker
    cv2.circle(image, (x0, y0), 30, (255, 255, 255), -1)
    ok, jpeg = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, 95])
    processor = FrameProcessor(320, 240, crop_border_fraction=0.15, jpeg_downscale=downscale)
    out = processor(jpeg.reshape(1, -1))
    assert out.shape == (240, 320, 3)
    row, col = blob_centroid(out, background=60)
    # crop 369 rows / 492 cols, then 1726 -> 240 rows and 2296 -> 320 cols
    expected_row = (y0 + 0.5 - 369) * 240 / 1726 - 0.5
    expected_col = (x0 + 0.5 - 492) * 320 / 2296 - 0.5
    assert row == pytest.approx(expected_row, abs=0.3)
    assert col == pytest.approx(expected_col, abs=0.3)


def test_crop_sizes_full_and_reduced() -> None:
    assert crop_borders(np.zeros((2464, 3280)), 0.15).shape == (1726, 2296)
    assert crop_borders(np.zeros((616, 820)), 0.15).shape == (432, 574)  # 1/4: 92.25 -> 92 rows


def test_digit_turn_matches_the_sdk() -> None:
    image = np.full((240, 320, 3), 60, np.uint8)
    r, c = 50, 200
    cv2.circle(image, (c, r), 6, (255, 255, 255), -1)
    out = FrameProcessor(240, 320, digit_orientation=True)(image)
    assert out.shape == (320, 240, 3)
    assert np.array_equal(out, orient_like_digit_sdk(image))
    assert np.array_equal(out, cv2.rotate(image, cv2.ROTATE_90_COUNTERCLOCKWISE))
    row, col = blob_centroid(out, background=60)
    assert (row, col) == pytest.approx((320 - 1 - c, r), abs=0.01)


# --- the driver on a video file ---------------------------------------------------------------


def test_digit_stream_from_decoding_capture(tmp_path: Path) -> None:
    frames = [textured(240, 320, seed=i) for i in range(20)]
    clip = write_avi(tmp_path / "digit.avi", frames)
    factory, made = paced_factory(raw=False, rate_hz=60)
    camera = TactileCamera(digit_config(by_id_dir(tmp_path, DIGIT_ID, clip)), factory)
    assert isinstance(camera, TactileSensor)
    with camera:
        assert camera.is_connected
        first = camera.read_latest(max_age_s=0.5)
        wait_for(lambda: camera.read_latest(0.5).t_s > first.t_s)
        second = camera.read_latest(max_age_s=0.5)
    assert not camera.is_connected
    assert isinstance(first, TactileFrame) and first.image.shape == (320, 240, 3)
    assert first.image.dtype == np.uint8 and not first.image.flags.writeable
    assert 0 < second.t_s - first.t_s < 0.5
    # the image is one of the clip's frames, turned like the SDK does
    diffs = [np.abs(orient_like_digit_sdk(f).astype(int) - first.image).mean() for f in frames]
    assert min(diffs) < 3.0
    assert made[0]._inner.isOpened() is False  # released on disconnect


def test_mini_raw_mjpeg_path_matches_full_decode(tmp_path: Path) -> None:
    frames = [textured(2464, 3280, seed=i) for i in range(3)]
    clip = write_avi(tmp_path / "mini.avi", frames)
    images = {}
    for raw in (True, False):
        factory, _ = paced_factory(raw=raw, rate_hz=20)
        with TactileCamera(
            mini_config(by_id_dir(tmp_path / str(raw), MINI_ID, clip)), factory
        ) as cam:
            images[raw] = cam.read_latest(max_age_s=1.0).image
    assert images[True].shape == images[False].shape == (240, 320, 3)
    # 1/4 DCT-scaled decode vs FFmpeg full decode + INTER_AREA: same picture
    assert np.abs(images[True].astype(int) - images[False]).mean() < 3.0


def test_compressed_frames_are_encoded_on_the_grabber_thread(tmp_path: Path) -> None:
    def jpeg(image: np.ndarray) -> bytes:
        return cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, 80])[1].tobytes()

    clip = write_avi(tmp_path / "digit.avi", [textured(240, 320, seed=i) for i in range(20)])
    factory, _ = paced_factory(raw=True, rate_hz=100)
    with TactileCamera(digit_config(by_id_dir(tmp_path, DIGIT_ID, clip)), factory) as camera:
        assert camera.read_latest(max_age_s=0.5).jpeg is None
        camera.compress_frames(jpeg)
        wait_for(lambda: camera.read_latest(0.5).jpeg is not None)
        frame = camera.read_latest(max_age_s=0.5)
        assert frame.jpeg == jpeg(frame.image)
        assert camera.compressed(frame.image) is frame.jpeg
        assert camera.compressed(frame.image.copy()) is None


def test_stale_frame_raises_timeout_and_recovers(tmp_path: Path) -> None:
    clip = write_avi(tmp_path / "digit.avi", [textured(240, 320, seed=i) for i in range(10)])
    factory, made = paced_factory(raw=True, rate_hz=100)
    with TactileCamera(digit_config(by_id_dir(tmp_path, DIGIT_ID, clip)), factory) as camera:
        camera.read_latest(max_age_s=0.2)
        made[0].pause()
        time.sleep(0.15)
        with pytest.raises(DeviceTimeoutError, match="ms old"):
            camera.read_latest(max_age_s=0.1)
        assert camera.is_connected
        made[0].resume()
        wait_for(lambda: not raises_now(camera, DeviceTimeoutError, max_age_s=0.1))


def test_frames_are_stamped_and_aged_on_the_injected_clock(tmp_path: Path) -> None:
    clip = write_avi(tmp_path / "digit.avi", [textured(240, 320, seed=i) for i in range(10)])
    factory, made = paced_factory(raw=True, rate_hz=100)
    clock = ManualClock(10.0)
    config = digit_config(by_id_dir(tmp_path, DIGIT_ID, clip))
    with TactileCamera(config, factory, clock) as camera:
        assert camera.read_latest(max_age_s=0.5).t_s == 10.0
        made[0].pause()
        time.sleep(0.2)  # let a grab in progress finish
        clock.advance(1.0)
        with pytest.raises(DeviceTimeoutError, match="1000 ms old"):
            camera.read_latest(max_age_s=0.5)
        made[0].resume()
        wait_for(lambda: not raises_now(camera, DeviceTimeoutError, max_age_s=0.5))
        assert camera.read_latest(max_age_s=0.5).t_s == 11.0


def test_frozen_stream_is_a_fault(tmp_path: Path) -> None:
    still = textured(240, 320, seed=7)
    clip = write_avi(tmp_path / "still.avi", [still] * 4)  # looped: the same frame forever
    factory, _ = paced_factory(raw=True, rate_hz=200)
    config = digit_config(by_id_dir(tmp_path, DIGIT_ID, clip), frozen_frame_count=6)
    with TactileCamera(config, factory) as camera:
        wait_for(lambda: raises_now(camera, DeviceFaultError))
        with pytest.raises(DeviceFaultError, match="frozen stream") as info:
            camera.read_latest(max_age_s=1.0)
        assert info.value.device == "tactile_camera"


def test_changing_stream_is_not_frozen(tmp_path: Path) -> None:
    clip = write_avi(tmp_path / "live.avi", [textured(240, 320, seed=i) for i in range(3)])
    factory, _ = paced_factory(raw=True, rate_hz=200)
    config = digit_config(by_id_dir(tmp_path, DIGIT_ID, clip), frozen_frame_count=2)
    images = []
    with TactileCamera(config, factory) as camera:
        t_end = time.monotonic() + 0.2
        while time.monotonic() < t_end:
            images.append(camera.read_latest(max_age_s=0.5).image)  # a fault would raise
            time.sleep(0.01)
        assert camera.is_connected
    assert len(images) >= 10
    assert len({image.tobytes() for image in images}) >= 2  # the stream really changed


def test_end_of_stream_is_a_disconnect(tmp_path: Path) -> None:
    clip = write_avi(tmp_path / "short.avi", [textured(240, 320, seed=i) for i in range(8)])
    factory, _ = paced_factory(raw=True, rate_hz=100, loop=False)
    camera = TactileCamera(digit_config(by_id_dir(tmp_path, DIGIT_ID, clip)), factory)
    camera.connect()
    wait_for(lambda: raises_now(camera, DeviceNotConnectedError))
    assert not camera.is_connected
    with pytest.raises(DeviceNotConnectedError, match="5 frame grabs in a row failed"):
        camera.read_latest(max_age_s=1.0)
    camera.disconnect()
    camera.disconnect()  # idempotent
    with pytest.raises(DeviceNotConnectedError, match="call connect"):
        camera.read_latest(max_age_s=1.0)
    camera.connect()  # the "device" is back: reconnect works
    assert camera.read_latest(max_age_s=1.0).image.shape == (320, 240, 3)
    camera.disconnect()


def test_vanished_device_node_is_reported(tmp_path: Path) -> None:
    clip = write_avi(tmp_path / "short.avi", [textured(240, 320, seed=i) for i in range(8)])
    factory, _ = paced_factory(raw=True, rate_hz=100, loop=False)
    config = digit_config(by_id_dir(tmp_path, DIGIT_ID, clip), max_read_failures=10_000)
    with TactileCamera(config, factory) as camera:
        os.remove(clip)  # "unplugged": the node disappears; the open capture reads on
        wait_for(lambda: raises_now(camera, DeviceNotConnectedError))
        with pytest.raises(DeviceNotConnectedError, match=f"{clip} is gone"):
            camera.read_latest(max_age_s=1.0)


def test_connect_errors(tmp_path: Path) -> None:
    clip = write_avi(tmp_path / "digit.avi", [textured(240, 320, seed=0)] * 2)
    d = by_id_dir(tmp_path, DIGIT_ID, clip)
    camera = TactileCamera(digit_config(d, by_id_pattern="*GelSight*"), paced_factory(False)[0])
    with pytest.raises(DeviceNotConnectedError, match="found: "):
        camera.connect()
    not_video = tmp_path / "not-video"
    not_video.write_bytes(b"plain text, no video")
    (d / f"{DIGIT_ID}0").unlink()
    (d / f"{DIGIT_ID}0").symlink_to(not_video)
    camera = TactileCamera(digit_config(d), lambda node: cv2.VideoCapture(node, cv2.CAP_FFMPEG))
    with pytest.raises(DeviceNotConnectedError, match="cannot open"):
        camera.connect()
    assert not camera.is_connected


def test_no_frame_before_timeout_is_a_timeout(tmp_path: Path) -> None:
    clip = write_avi(tmp_path / "digit.avi", [textured(240, 320, seed=0)] * 4)
    d = by_id_dir(tmp_path, DIGIT_ID, clip)
    factory, made = paced_factory(raw=True, rate_hz=100)

    def paused_factory(node: str) -> PacedCapture:
        cap = factory(node)
        cap.pause()
        threading.Timer(0.3, cap.resume).start()  # let the grabber thread end afterwards
        return cap

    camera = TactileCamera(digit_config(d, connect_timeout_s=0.1), paused_factory)
    with pytest.raises(DeviceTimeoutError, match="no usable frame within 0.1 s"):
        camera.connect()
    assert not camera.is_connected


def test_a_camera_whose_open_hangs_fails_connect_in_time(tmp_path: Path) -> None:
    """Opening runs on the grabber thread: a driver stuck in open() costs connect_timeout_s,
    and the capture is released once the open returns."""
    clip = write_avi(tmp_path / "digit.avi", [textured(240, 320, seed=0)] * 4)
    d = by_id_dir(tmp_path, DIGIT_ID, clip)
    unblock = threading.Event()
    factory, made = paced_factory(raw=True, rate_hz=100)

    def hanging_factory(node: str) -> PacedCapture:
        unblock.wait(10.0)  # as a V4L2 open that never returns
        return factory(node)

    camera = TactileCamera(digit_config(d, connect_timeout_s=0.2), hanging_factory)
    started = time.monotonic()
    with pytest.raises(DeviceTimeoutError, match=r"opening .* did not finish within 0.2 s"):
        camera.connect()
    assert time.monotonic() - started < 0.2 + 1.0  # the deadline plus a margin, no join
    assert not camera.is_connected
    grabbers = [t for t in threading.enumerate() if t.name == "tactile_camera-grabber"]
    unblock.set()
    for thread in grabbers:
        thread.join(3.0)
        assert not thread.is_alive()
    assert len(made) == 1 and not made[0].isOpened()  # released by the thread


def test_registry_builds_the_real_driver_for_a_video_peer(tmp_path: Path) -> None:
    clip = write_avi(tmp_path / "digit.avi", [textured(240, 320, seed=i) for i in range(10)])
    factory, _ = paced_factory(raw=False, rate_hz=60)
    data = yaml.safe_load((REPO / "configs" / "sensors" / "digit_camera.yaml").read_text())
    data.update(by_id_dir=str(by_id_dir(tmp_path, DIGIT_ID, clip)), connect_timeout_s=2.0)
    path = tmp_path / "digit_camera.yaml"
    path.write_text(yaml.safe_dump(data))
    with load_device(path, backend="real", kind="tactile", capture_factory=factory) as camera:
        assert isinstance(camera, TactileCamera)
        frame = camera.read_latest(max_age_s=0.5)
    assert frame.image.shape == (320, 240, 3)
