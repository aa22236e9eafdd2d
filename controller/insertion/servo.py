"""The servos ALIGN and INSERT share: yielding to the tactile torques, pressing with a
bounded load, and the yaw sweep (config.AlignSettings, config.InsertSettings).

Torques and loads are the filtered normalised signals (noise units, ``signals.py``);
angular velocities are in B (rad/s), tip speeds in m/s.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from controller.insertion.machine_config import AlignSettings
from controller.insertion.signals import TactileSignals
from core.spatial import tilt_of_tool_axis, tool_z_in_base


def torque_tolerance(settings: AlignSettings) -> np.ndarray:
    """ALIGN's tolerances on the normalised torques (tau_x, tau_y, tau_z), noise units."""
    return np.array([settings.tol_tau_x_sigma, settings.tol_tau_y_sigma, settings.tol_tau_z_sigma])


def torques_within_tolerance(signals: TactileSignals, settings: AlignSettings) -> bool:
    """True when every normalised torque is within its tolerance."""
    return bool(np.all(np.abs(signals.normalised[:3]) <= torque_tolerance(settings)))


def align_rate(
    signals: TactileSignals, settings: AlignSettings, rotation: Rotation, scale: float
) -> np.ndarray:
    """Angular velocity in B yielding to the torques outside tolerance: w_T = -R_S2T k
    n_S, scaled (config.AlignSettings); at ``align.servo_tilt_max_rad`` from straight
    down or more, without the part that would tilt the TCP (T2B ``rotation``) further."""
    gains = np.array([settings.gain_tau_x, settings.gain_tau_y, settings.gain_tau_z])
    tolerance = torque_tolerance(settings)
    torque_s = signals.normalised[:3]
    outside = np.where(np.abs(torque_s) > tolerance, torque_s, 0.0)
    w = rotation.apply(-signals.s2t @ (gains * outside) * scale)
    angle, upright = tilt_of_tool_axis(tool_z_in_base(rotation))  # w along it: uprights
    if angle >= settings.servo_tilt_max_rad:
        w = w - min(0.0, float(w @ upright)) * upright
    return w


def heel_yaw_rate(
    signals: TactileSignals, settings: AlignSettings, rotation: Rotation
) -> np.ndarray:
    """Angular velocity in B yielding in yaw (about T z) to the torque about the plug's
    axis while the heel is caught (``align.heel_yaw_gain``)."""
    about_t_z = float(signals.torque_t[2])
    return rotation.apply([0.0, 0.0, -settings.heel_yaw_gain * about_t_z])


def load_rate(signals: TactileSignals, load_sigma: float, speed_m_s: float) -> float:
    """Downward tip speed (m/s) holding the axial load at ``load_sigma`` (noise units):
    ``speed_m_s`` times the load's shortfall relative to it, within +-1."""
    shortfall = (load_sigma - signals.axial_force_sigma) / load_sigma
    return speed_m_s * float(np.clip(shortfall, -1.0, 1.0))


@dataclass
class YawSweep:
    """A triangle wave of the plug's yaw within +-``sweep_rad`` of the opening's nominal
    yaw (ALIGN's yaw stage, INSERT's press): ``sign`` the present direction, ``reversals``
    the turns so far, ``start_yaw_rad`` the yaw (from the nominal) where it began."""

    sign: float = 1.0
    reversals: int = 0
    start_yaw_rad: float = 0.0

    def advance(self, yaw_rad: float, sweep_rad: float, sweeps: int) -> bool:
        """Take the present yaw (rad, from the nominal): turn at +-``sweep_rad``; True once
        ``sweeps`` whole sweeps are done and the yaw is back where the sweep began."""
        if self.sign * yaw_rad >= sweep_rad:
            self.sign = -self.sign
            self.reversals += 1
        return self.reversals >= 2 * sweeps and (self.sign * (yaw_rad - self.start_yaw_rad) >= 0.0)
