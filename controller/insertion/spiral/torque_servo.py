"""INSERT's yield to the plug's torques while it pushes (the press-spiral machine on touch):
the TCP turns about the plug's tip so that the torques the fingers feel go to zero, w_T =
-k * tau_T (each of T's axes its own gain), the tip held where the catch found it.

A plug tilted in the hand, or at a yaw off the opening's, meets the opening's walls off its
axis: the push then loads the fingers with a torque about the grasp, which the servo turns
away, uprighting the plug in the opening (about T x and T y) and yielding in yaw to the
torque about its axis (T z). The turn is capped at ``max_rate_rad_s`` and goes no further
than ``max_turn_rad`` from the pass's orientation. Torques in N*m, in T; rates in rad/s.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from controller.insertion.motion import rotation_error
from core.config import Config, config_dataclass, number
from core.spatial import clamp_norm


@config_dataclass
class TorqueServoSettings(Config):
    """The task's ``touch_spiral.push_servo:``: ``gain_rad_s_nm``, the turn's rate per N*m
    of the torque about T x, T y and T z (zeros: no servo, the plug held at the pass's
    orientation); ``max_rate_rad_s``, the turn's rate cap (rad/s); ``max_turn_rad``: the farthest
    the servo turns the TCP from the pass's orientation (rad)."""

    gain_rad_s_nm: tuple[float, float, float] = (0.0, 0.0, 0.0)
    max_rate_rad_s: float = number(0.0, 2.0, default=0.2)
    max_turn_rad: float = number(0.0, 0.5, default=0.1)

    def __post_init__(self) -> None:
        if any(not (0.0 <= g <= 1e4) for g in self.gain_rad_s_nm):
            raise ValueError(
                f"key 'gain_rad_s_nm': expected gains in [0, 10000], got {self.gain_rad_s_nm}"
            )

    @property
    def on(self) -> bool:
        """Any gain is set."""
        return any(g > 0.0 for g in self.gain_rad_s_nm)


@dataclass(frozen=True)
class TorqueServo:
    """The servo (see the module doc) for ``settings``."""

    settings: TorqueServoSettings

    def rate_b(self, torque_t: np.ndarray, t2b: Rotation, reference: Rotation) -> np.ndarray:
        """The angular velocity in B (rad/s) for the torque ``torque_t`` (N*m, in T) with the
        TCP turned by ``t2b``; the part that would turn it further from ``reference`` (T2B)
        is dropped once it is ``max_turn_rad`` away."""
        s = self.settings
        w = t2b.apply(-np.asarray(s.gain_rad_s_nm) * np.asarray(torque_t, dtype=float))
        back = rotation_error(t2b, reference)  # turns the TCP back to the reference
        away = float(np.linalg.norm(back))
        if away >= s.max_turn_rad and away > 0.0:
            toward = back / away
            w = w - min(0.0, float(w @ toward)) * toward
        return clamp_norm(w, s.max_rate_rad_s)
