"""Tactile estimation: camera frames -> displacement field -> wrench estimate.

The public API; the modules behind it hold the steps (flow, field, nhhd, dipole, baseline,
slip, calibration). Build an estimator for a sensor and push frames::

    from controller.tactile import estimator_for_sensor

    est = estimator_for_sensor("gelsight_mini")  # the profile's own configuration
    est.capture_open(4)  # gripper open, gel free: the next 4 pushed frames (optional)
    est.rezero(5)  # after the grasp: the next 5 frames become the reference
    estimate = est.push(frame_bgr, t_s)  # -> WrenchEstimate

With the open gel seen first, ``grasp_centroid`` configurations (``grid_lk``) take the tilt
about the contact's centre, which a swinging grip pressure does not disturb
(``est.contact_centre_mm``); without it they use the centroid-midpoint rule. Offline:
``est.set_open_reference(frames)`` and ``est.set_reference(frames)``.

The control loop takes any ``WrenchSource`` (``push``, ``capture_open``, ``rezero``); the
estimator is one.
"""

from controller.tactile.calibration import Calibration
from controller.tactile.estimator import TactileEstimator, estimator_for_sensor
from controller.tactile.field import VectorField
from controller.tactile.settings import EstimatorConfig, estimator_config
from controller.tactile.slip import RezeroState, SlipStatus
from controller.tactile.wrench import WrenchEstimate
from controller.tactile.wrench_source import TransformedSource, WrenchSource

__all__ = [
    "Calibration",
    "EstimatorConfig",
    "RezeroState",
    "SlipStatus",
    "TactileEstimator",
    "TransformedSource",
    "VectorField",
    "WrenchEstimate",
    "WrenchSource",
    "estimator_config",
    "estimator_for_sensor",
]
