"""A scripted synthetic tactile sequence with known patterns, for the offline demo.

Each phase drives one analytic displacement pattern with a smooth back-and-forth amplitude:

* ``tilt_x``: a positive 'charge' (gel spreading) toward +y and a negative one toward -y,
  the divergence dipole of a torque about S's x axis; ``tilt_y`` likewise along x, with the
  sign of a torque about y (more pressure toward +x is a negative tau_y);
* ``twist``: a rigid rotation of the contact patch, positive from +x toward +y (the gel's
  tau_z on the object is then negative);
* ``shear``: a translation of the contact patch along +x.

The truth is the pattern's signed amplitude in [-1, 1], not a wrench: these are analytic
fields chosen to exercise the estimator's sign conventions and linearity, not the gel
physics (that is the gel simulator's job).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

PHASES = ("rest", "tilt_x", "tilt_y", "twist", "shear")


@dataclass(frozen=True)
class SyntheticFrame:
    """One frame's time (s), active phase, signed amplitude in [-1, 1] and forward field
    (H, W, 2) in px."""

    t_s: float
    phase: str
    amplitude: float
    displacement_px: np.ndarray


def _charge(xs: np.ndarray, ys: np.ndarray, cx: float, cy: float, width: float) -> np.ndarray:
    """Unit-peak field of a Gaussian charge at (cx, cy) px (see
    tests/controller/tactile/fields.py)."""
    dx, dy = xs - cx, ys - cy
    r2 = np.maximum(dx**2 + dy**2, 1e-9)
    k = -np.expm1(-r2 / (2 * width**2)) / r2
    field = np.stack([k * dx, k * dy], axis=-1)
    return field / np.hypot(field[..., 0], field[..., 1]).max()


def phase_patterns(shape_hw: tuple[int, int], peak_px: float = 1.5) -> dict[str, np.ndarray]:
    """Each phase's pattern at amplitude +1: a forward field (H, W, 2) in px with the given
    peak displacement."""
    height, width = shape_hw
    ys, xs = np.mgrid[0:height, 0:width].astype(np.float64)
    cx, cy = width / 2, height / 2
    sep, w = 0.22 * height, 0.1 * height
    patch = np.exp(-((xs - cx) ** 2 + (ys - cy) ** 2) / (2 * (0.25 * height) ** 2))
    patterns = {
        "tilt_x": _charge(xs, ys, cx, cy + sep, w) - _charge(xs, ys, cx, cy - sep, w),
        "tilt_y": _charge(xs, ys, cx + sep, cy, w) - _charge(xs, ys, cx - sep, cy, w),
        "twist": np.stack([-(ys - cy) * patch, (xs - cx) * patch], axis=-1),
        "shear": np.stack([patch, np.zeros_like(patch)], axis=-1),
    }
    for name, field in patterns.items():
        peak = np.hypot(field[..., 0], field[..., 1]).max()
        patterns[name] = (field * (peak_px / peak)).astype(np.float32)
    patterns["tilt_y"] *= -1.0  # more pressure toward +x is a negative torque about y
    return patterns


def demo_sequence(
    shape_hw: tuple[int, int] = (240, 320),
    fps_hz: float = 25.0,
    phase_s: float = 2.4,
    rest_s: float = 0.8,
    peak_px: float = 1.5,
) -> list[SyntheticFrame]:
    """Rest, then each pattern through one full sine period of amplitude, in turn."""
    patterns = phase_patterns(shape_hw, peak_px)
    frames = []
    zero = np.zeros((*shape_hw, 2), np.float32)
    t = 0.0
    dt = 1.0 / fps_hz
    for _ in range(round(rest_s * fps_hz)):
        frames.append(SyntheticFrame(t, "rest", 0.0, zero))
        t += dt
    for phase in PHASES[1:]:
        n = round(phase_s * fps_hz)
        for i in range(n):
            amplitude = float(np.sin(2 * np.pi * i / n))
            frames.append(SyntheticFrame(t, phase, amplitude, amplitude * patterns[phase]))
            t += dt
    return frames
