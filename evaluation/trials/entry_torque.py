"""The torques the opening's walls put on the plug as it goes in, from the scene's truth:
what the push under the torque servo drives toward zero (docs/BENCHMARKS.md).

The truth's ``gel_wrench_s`` is the wrench the sensing finger's gel exerts on the plug, in
S about S's origin (drivers/sim/scenes/insertion/truth.py). Its torques include the hold
(the grip's moment and the plug's weight), so the reference is their median over the
``BASELINE_S`` before the plug first touches anything (``contact_force_n`` > 0): the plug
held in the air. The entry is every truth row whose tip is ``ENTERED_M`` or more into the
opening and not yet at the task's depth; the press on the board never sinks the tip that
far, a catch does. Controller-independent: every trial is scored alike, whatever its phases.
"""

from __future__ import annotations

import math

import numpy as np

ENTERED_M = 0.001
"""The tip this far (m) below the board's surface is in the opening."""

BASELINE_S = 0.3
"""The hold's torques are the median over this long (s) before the first contact."""


def entry_torques(truth: dict[str, np.ndarray], depth_m: float) -> tuple[float, float]:
    """(tilt, in-plane): the RMS over the entry's truth rows of the change, from the hold
    in the air, of the gel's torque about S x and S y together (its magnitude) and about S
    z (N*m); nan, nan when the tip never entered short of ``depth_m`` (m) or the plug
    touched from the first row on."""
    t, contact, depth = truth["t_s"], truth["contact_force_n"], truth["depth_m"]
    touched = np.flatnonzero(contact > 0.0)
    entry = (depth >= ENTERED_M) & (depth < depth_m)
    if not touched.size or touched[0] == 0 or not entry.any():
        return math.nan, math.nan
    first = int(touched[0])
    torque = np.asarray(truth["gel_wrench_s"])[:, 3:6]
    held = torque[:first][t[:first] >= t[first - 1] - BASELINE_S]
    change = torque[entry] - np.median(held, axis=0)
    tilt = np.linalg.norm(change[:, :2], axis=1)
    return float(np.sqrt(np.mean(tilt**2))), float(np.sqrt(np.mean(change[:, 2] ** 2)))
