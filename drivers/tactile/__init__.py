"""Visuotactile cameras (GelSight Mini, DIGIT) through OpenCV's V4L2 backend, and the sensor
profiles (``drivers.tactile.profile``: the geometry of each sensor's working image).

The camera driver is imported on first use, so the controller can read sensor profiles
without loading a driver.
"""

from __future__ import annotations

import importlib
from typing import Any

__all__ = ["TactileCamera", "TactileCameraConfig", "open_v4l2"]


def __getattr__(name: str) -> Any:
    if name in __all__:
        return getattr(importlib.import_module("drivers.tactile.camera"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
