"""SEARCH's path and its hole-found rule.

``SearchPattern`` is the planar path the tip is dragged along; ``HoleDetector`` watches the
drag resistance for the signature of the tip dropping into the opening's edge
(config.SearchSettings gives the rule and its keys; docs/ARCHITECTURE.md the formulas).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial.transform import Rotation

from controller.insertion.machine_config import SearchSettings
from controller.insertion.signals import TactileSignals
from core.spatial import cross


def lateral_resistance(
    signals: TactileSignals, rotation: Rotation, direction_b: np.ndarray
) -> tuple[int, float]:
    """How hard the surroundings resist the tip's horizontal motion along ``direction_b``
    (in B; any length), in noise units, from the tilt torques: a force against the motion
    at the tip acts on the plug's length about e = z_T x d (d the motion's direction), which
    lies in T's x-y plane. The tool axis a (0: T x, 1: T y) with the larger |e_a| measures it:
    r = n_a / e_a (n the normalised torque in T), positive when resisting. Returns (a, r)."""
    axis_b = cross(rotation.apply([0.0, 0.0, 1.0]), direction_b)
    e_t = rotation.inv().apply(axis_b / np.linalg.norm(axis_b))
    a = int(np.argmax(np.abs(e_t[:2])))
    return a, float(signals.torque_t[a] / e_t[a])


class SearchPattern:
    """A planar search path in the opening's frame (u along its width axis, v across),
    centred on the nominal opening and parameterised by the path length s (m). Past its end
    the path is run backwards and forwards again (a triangle wave in s), so the tip never
    jumps.

    ``spiral``: Archimedean, r = pitch theta / (2 pi), out to radius sqrt(2) half_width
    (the corners of the uncertainty square); s ~ pitch theta^2 / (4 pi).
    ``raster``: from the centre straight to the corner (-half_width, -half_width), then lines
    along u from -half_width to half_width, ``pitch`` apart in v.
    """

    def __init__(self, kind: str, pitch_m: float, half_width_m: float) -> None:
        self.kind = kind
        self.pitch_m = pitch_m
        self.half_width_m = half_width_m
        if kind == "spiral":
            self._a = pitch_m / (2.0 * math.pi)
            theta_max = math.sqrt(2.0) * half_width_m / self._a
            self.length_m = self._a * theta_max**2 / 2.0
        else:
            self._lines = int(math.floor(2.0 * half_width_m / pitch_m + 1e-9)) + 1
            self._lead_m = math.sqrt(2.0) * half_width_m
            span = 2.0 * half_width_m
            self.length_m = self._lead_m + self._lines * span + (self._lines - 1) * pitch_m

    def offset(self, s_m: float) -> np.ndarray:
        """(u, v) offset in m at path length ``s_m`` (folded into the path)."""
        if self.length_m <= 0.0:
            return np.zeros(2)
        period = 2.0 * self.length_m
        s = math.fmod(max(s_m, 0.0), period)
        s = period - s if s > self.length_m else s
        return self._spiral(s) if self.kind == "spiral" else self._raster(s)

    def _spiral(self, s: float) -> np.ndarray:
        theta = math.sqrt(2.0 * s / self._a)
        r = self._a * theta
        return np.array([r * math.cos(theta), r * math.sin(theta)])

    def _raster(self, s: float) -> np.ndarray:
        if s < self._lead_m:
            return -np.full(2, s / math.sqrt(2.0))
        s -= self._lead_m
        span = 2.0 * self.half_width_m
        unit = span + self.pitch_m
        line = min(int(s // unit), self._lines - 1)
        along = s - line * unit
        v = -self.half_width_m + line * self.pitch_m
        if along > span:  # the step to the next line
            v += along - span
            along = span
        u = -self.half_width_m + along if line % 2 == 0 else self.half_width_m - along
        return np.array([u, v])


class HoleDetector:
    """The drag resistance rule, fed once per new tactile estimate (``update``).

    The drag direction d is the tip's commanded horizontal velocity in B, filtered like the
    signals (so its lag matches theirs); the rule is judged only while dragging steadily (d
    at least ``steady_speed_ratio`` of the search speed and within
    acos(``steady_cosine``) of the latest command). The friction torque's axis e = z_T x d
    lies in T's x-y plane; the tool axis a with the larger |e_a| measures the resistance
    r = n_a / e_a (n the normalised torque in T), so r is the same for any drag direction
    served by that axis even though the two axes are measured by different estimators (T x:
    a dipole tilt torque, T y: the NHHD in-plane torque, by default). Friction grows with
    the load, so each axis keeps as its reference the ratio of r to the load L (the
    normalised axial force, at least ``min_load_sigma``): learned (weight ``ema_alpha``)
    over its first ``hole_frames`` judged samples and the first ``settle_s`` of SEARCH, then
    followed slowly (``reference_alpha``) while r is not rising. Hole found: r - ratio x L
    >= max(``hole_rise_sigma``, ``hole_rise_ratio`` x |ratio x L|) for ``hole_frames``
    successive judged samples.
    """

    def __init__(self, settings: SearchSettings, ema_alpha: float) -> None:
        self._settings = settings
        self._alpha = ema_alpha
        self._ratios: list[float | None] = [None, None]
        self._learned = [0, 0]
        self._count = 0
        self._drag = np.zeros(3)
        self._load_ref: float | None = None
        self._load_samples = 0
        self._drop_count = 0

    def update(
        self,
        signals: TactileSignals,
        rotation: Rotation,
        commanded: np.ndarray,
        elapsed_s: float,
    ) -> str:
        """The rules that hold after this estimate: ``torque_catch`` (the drag resistance's
        rise), ``load_drop`` (the axial force's fall), both joined by ``+``, or "" for
        none; ``commanded``: the tip velocity in B last commanded, ``elapsed_s``: time since
        SEARCH began."""
        caught = self._judge(signals, rotation, commanded, elapsed_s)
        dropped = self._dropped(signals.axial_force_sigma, elapsed_s)
        horizontal = np.array([commanded[0], commanded[1], 0.0])
        self._drag = self._alpha * horizontal + (1.0 - self._alpha) * self._drag
        return "+".join(
            name for name, fired in (("torque_catch", caught), ("load_drop", dropped)) if fired
        )

    @property
    def load_reference(self) -> float | None:
        """The axial force's reference (noise units): the preload while dragging."""
        return self._load_ref

    def _dropped(self, load: float, elapsed_s: float) -> bool:
        """The load-drop rule (config.SearchSettings): the axial force fallen below
        (1 - ``hole_drop_ratio``) x its reference, and by ``hole_drop_sigma``."""
        settings = self._settings
        if settings.hole_drop_ratio <= 0.0:
            return False
        ref = self._load_ref
        self._load_samples += 1
        if (
            ref is None
            or self._load_samples <= settings.hole_frames
            or (elapsed_s < settings.settle_s)
        ):
            previous = load if ref is None else ref
            self._load_ref = self._alpha * load + (1.0 - self._alpha) * previous
            self._drop_count = 0
            return False
        dropping = load <= (1.0 - settings.hole_drop_ratio) * ref and (
            ref - load >= settings.hole_drop_sigma
        )
        self._drop_count = self._drop_count + 1 if dropping else 0
        if not dropping:
            slow = settings.reference_alpha
            self._load_ref = slow * load + (1.0 - slow) * ref
        return self._drop_count >= settings.hole_frames

    def _judge(
        self, signals: TactileSignals, rotation: Rotation, commanded: np.ndarray, elapsed_s: float
    ) -> bool:
        settings, drag = self._settings, self._drag
        speed = float(np.linalg.norm(drag))
        horizontal = np.array([commanded[0], commanded[1], 0.0])
        if speed < settings.steady_speed_ratio * settings.speed_m_s or np.dot(
            drag, horizontal
        ) < settings.steady_cosine * (speed * np.linalg.norm(horizontal)):
            self._count = 0
            return False
        a, resistance = lateral_resistance(signals, rotation, drag)
        load = max(signals.axial_force_sigma, settings.min_load_sigma)
        ratio = self._ratios[a]
        self._learned[a] += 1
        if (
            ratio is None
            or self._learned[a] <= settings.hole_frames
            or (elapsed_s < settings.settle_s)
        ):
            previous = resistance / load if ratio is None else ratio
            self._ratios[a] = self._alpha * resistance / load + (1.0 - self._alpha) * previous
            self._count = 0
            return False
        expected = ratio * load
        rising = resistance - expected >= max(
            settings.hole_rise_sigma, settings.hole_rise_ratio * abs(expected)
        )
        self._count = self._count + 1 if rising else 0
        if not rising:
            slow = settings.reference_alpha
            self._ratios[a] = slow * resistance / load + (1.0 - slow) * ratio
        return self._count >= settings.hole_frames
