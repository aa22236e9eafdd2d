"""Visuotactile cameras (GelSight Mini, DIGIT) through OpenCV's V4L2 backend."""

from drivers.tactile.camera import TactileCamera, TactileCameraConfig, open_v4l2

__all__ = ["TactileCamera", "TactileCameraConfig", "open_v4l2"]
