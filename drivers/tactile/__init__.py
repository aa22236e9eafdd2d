"""Visuotactile cameras (GelSight Mini, DIGIT) through OpenCV's V4L2 backend. The sensors'
image geometry (profiles) is in ``core.sensor_profile``."""

from drivers.tactile.camera import TactileCamera, TactileCameraConfig, open_v4l2

__all__ = ["TactileCamera", "TactileCameraConfig", "open_v4l2"]
