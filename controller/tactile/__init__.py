"""Tactile estimation: camera frames -> displacement field -> wrench estimate.

The public API; the modules behind it hold the steps (flow, field, nhhd, dipole, baseline,
slip, calibration). Build an estimator for a sensor and push frames::

    from controller.tactile import estimator_for_sensor

    est = estimator_for_sensor("gelsight_mini")  # the profile's own configuration
    est.rezero(5)  # after the grasp: the next 5 frames become the reference
    estimate = est.push(frame_bgr, t_s)  # -> WrenchEstimate
"""

from controller.tactile.calibration import Calibration
from controller.tactile.estimator import TactileEstimator, estimator_for_sensor
from controller.tactile.field import VectorField
from controller.tactile.settings import EstimatorConfig, estimator_config
from controller.tactile.slip import RezeroState, SlipStatus
from controller.tactile.wrench import WrenchEstimate

__all__ = [
    "Calibration",
    "EstimatorConfig",
    "RezeroState",
    "SlipStatus",
    "TactileEstimator",
    "VectorField",
    "WrenchEstimate",
    "estimator_config",
    "estimator_for_sensor",
]
