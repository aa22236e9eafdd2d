"""From what a tactile camera hands over to the image the estimator receives.

Two kinds of frames arrive:

* a compressed MJPG buffer: OpenCV's V4L2 backend with ``CAP_PROP_CONVERT_RGB = 0`` returns the
  buffer as dequeued, a ``1 x N`` uint8 array (``CvCaptureCAM_V4L::retrieveFrame`` in
  ``modules/videoio/src/cap_v4l.cpp``). We decode it at 1/2, 1/4 or 1/8 of full size with
  libjpeg's DCT scaling (``cv2.IMREAD_REDUCED_COLOR_*``), which skips most of the inverse DCT
  work on the GelSight Mini's 3280 x 2464 frames;
* an image the backend already decoded (H x W x 3 BGR), e.g. from a video file. It goes
  through the same crop, resize and orientation, at full resolution.

Geometry, all in image pixels (x along columns, y along rows):

1. crop: remove ``crop_border_fraction`` of the height and width from each border,
   ``int(size * fraction)`` pixels of the decoded image, as gsrobotics' ``crop_and_resize``
   does (its GelSight Mini default is 0.15); on a reduced decode this matches the
   full-resolution crop to within one decoded pixel;
2. resize to the output size with ``INTER_AREA`` (``INTER_LINEAR`` if enlarging);
3. orientation: DIGIT images are turned as digit-interface's ``Digit.get_frame()`` does by
   default, ``cv2.transpose`` then ``cv2.flip(..., 0)`` (a 90 degree counter-clockwise turn:
   input pixel (row r, col c) of a W-wide image lands at (row W - 1 - c, col r)).
"""

from __future__ import annotations

import math
import typing
from dataclasses import dataclass
from typing import Literal

import cv2
import numpy as np

JpegDownscale = Literal[1, 2, 4, 8]
JPEG_DOWNSCALES = typing.get_args(JpegDownscale)
_IMREAD_FLAGS = {
    1: cv2.IMREAD_COLOR,
    2: cv2.IMREAD_REDUCED_COLOR_2,
    4: cv2.IMREAD_REDUCED_COLOR_4,
    8: cv2.IMREAD_REDUCED_COLOR_8,
}


def is_jpeg_buffer(frame: np.ndarray) -> bool:
    """True for a compressed JPEG buffer: uint8, one row (or 1-D), starting with SOI FF D8."""
    one_row = frame.ndim == 1 or (frame.ndim == 2 and frame.shape[0] == 1)
    return (
        frame.dtype == np.uint8
        and one_row
        and frame.size >= 4
        and int(frame.flat[0]) == 0xFF
        and int(frame.flat[1]) == 0xD8
    )


def decode_jpeg(buffer: np.ndarray, downscale: int = 1) -> np.ndarray:
    """Decode a JPEG buffer to BGR uint8 at 1/``downscale`` size (ceil of each side).

    Raises ValueError if ``downscale`` is not 1, 2, 4 or 8 or the data does not decode.
    """
    if downscale not in _IMREAD_FLAGS:
        raise ValueError(f"jpeg downscale must be one of {JPEG_DOWNSCALES}, got {downscale!r}")
    try:
        image = cv2.imdecode(buffer, _IMREAD_FLAGS[downscale])
    except cv2.error as exc:
        raise ValueError(f"JPEG decode failed: {exc}") from exc
    if image is None:
        raise ValueError(f"JPEG decode failed ({buffer.size} bytes of corrupt or cut data)")
    return image


def cropped_size(width_px: int, height_px: int, fraction: float, downscale: int) -> tuple[int, int]:
    """(width, height) left after decoding a ``width_px`` x ``height_px`` JPEG at
    1/``downscale`` and cropping ``fraction`` off each border."""
    w, h = math.ceil(width_px / downscale), math.ceil(height_px / downscale)
    return w - 2 * int(w * fraction), h - 2 * int(h * fraction)


def crop_borders(image: np.ndarray, fraction: float) -> np.ndarray:
    """Remove ``int(size * fraction)`` pixels from each border (a view, no copy)."""
    h, w = image.shape[:2]
    by, bx = int(h * fraction), int(w * fraction)
    return image[by : h - by, bx : w - bx]


def resize_to(image: np.ndarray, width_px: int, height_px: int) -> np.ndarray:
    """Resize to ``width_px`` x ``height_px``: INTER_AREA when shrinking, INTER_LINEAR when
    enlarging; returns the image itself when it already has that size."""
    h, w = image.shape[:2]
    if (w, h) == (width_px, height_px):
        return image
    shrinking = width_px <= w and height_px <= h
    interpolation = cv2.INTER_AREA if shrinking else cv2.INTER_LINEAR
    return cv2.resize(image, (width_px, height_px), interpolation=interpolation)


def orient_like_digit_sdk(image: np.ndarray) -> np.ndarray:
    """digit-interface's default frame orientation: transpose, then flip about the x axis."""
    return cv2.flip(cv2.transpose(image), 0)


@dataclass(frozen=True)
class FrameProcessor:
    """Turns one captured frame into the output image (uint8, H x W x 3, BGR).

    ``output_width_px`` x ``output_height_px`` is the size of the returned image, after the
    DIGIT orientation when ``digit_orientation`` is set (so a 320 x 240 DIGIT stream gives a
    240 x 320 image). ``jpeg_downscale`` applies to compressed buffers only.
    """

    output_width_px: int
    output_height_px: int
    crop_border_fraction: float = 0.0
    jpeg_downscale: int = 1
    digit_orientation: bool = False

    def __call__(self, frame: np.ndarray) -> np.ndarray:
        """Raises ValueError on a frame that is neither a JPEG buffer nor a BGR image."""
        if is_jpeg_buffer(frame):
            image = decode_jpeg(frame, self.jpeg_downscale)
        elif frame.ndim == 3 and frame.shape[2] == 3 and frame.dtype == np.uint8:
            image = frame
        else:
            raise ValueError(
                f"unexpected frame layout {frame.shape} {frame.dtype}: "
                "expected a JPEG buffer or an H x W x 3 uint8 image"
            )
        return self.process_decoded(image)

    def process_decoded(self, image: np.ndarray) -> np.ndarray:
        """Crop, resize and orient a decoded BGR image."""
        cropped = crop_borders(image, self.crop_border_fraction)
        if self.digit_orientation:
            turned = resize_to(cropped, self.output_height_px, self.output_width_px)
            return orient_like_digit_sdk(turned)
        return np.ascontiguousarray(resize_to(cropped, self.output_width_px, self.output_height_px))
