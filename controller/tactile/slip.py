"""Incipient and gross slip from the zeroed displacement field alone, and when to re-zero.

**The physical picture** (Cattaneo-Mindlin partial slip; the brush model): under a growing
in-plane load, slip starts where the contact pressure, and so the friction limit, is lowest,
at the edges of the contact, and spreads inward. The slipping cells carry a traction already
at the friction limit, so each further load increment is carried by the stuck core alone: the
stuck core keeps moving rigidly with the object while the slipping periphery lags behind.
GelSlim's detector (Dong, Ma, Donlon & Rodriguez, ICRA 2019) fits a rigid 2-D motion to the
markers of the contact and thresholds the residual; Dong, Yuan & Adelson (IROS 2017) compare
the peripheral with the global marker displacement. Once the stuck core vanishes the object
slides as a whole (gross slip): the traction saturates, so the tangential field stops
growing (or relaxes, when kinetic friction is lower than static friction).

**The features used here**, chosen by measurement on the simulated gel against the
alternatives below (evaluation/experiments/slip_eval.py; docs/EVALUATION.md gives the numbers):

1. Only the divergence-free part of the field (the NHHD rotational plus harmonic parts,
   ``t = v - d``) is watched. Normal-load and tilt changes live mostly in the diverging
   part ``d`` and would otherwise read as non-rigid motion.
2. The detector looks at *increments*: each time ``t`` has moved by ``min_increment_mm``
   (largest cell) since the last evaluation, it takes the increment over the contact core,
   the cells where ``|t|`` is at least ``core_fraction`` of its largest value. Increments
   make the measure independent of the loading rate and of the load already carried.
3. Only **loading** increments are judged: slip can only spread while the tangential load
   grows along its own direction, so the increment's rigid motion (translation and
   rotation times the core's radius of gyration) must point within acos(``loading_cosine``)
   of the rigid motion of ``t`` itself. Tilts, grip changes, unloading and a load turning
   sideways are skipped (the increment still restarts from there). A loading increment
   must also **move the stuck core rigidly**: its rigid motion at least
   ``min_rigid_fraction`` of its RMS over the core. A change of the normal load (pushing,
   pressing) leaks into ``t`` through the flow's errors and the decomposition's harmonic
   part as a non-affine pattern that grows with the load, nearly along itself, so it passed
   the direction test with a large residual; its rigid part is 4-25% of its RMS on
   realistic images, a real tangential increment's 95-98%
   (evaluation/experiments/slip_false_alarms.py).
   Under slip the affine residual r bounds the rigid fraction by sqrt(1 - r^2), so the gate
   at 0.5 still judges residuals up to 0.87. Cores of fewer than ``MIN_CORE_CELLS`` cells
   (an affine fit explains them exactly) are not judged either.
4. The **residual** is the RMS misfit of an affine motion (least squares: translation,
   rotation, uniform expansion, two stretches) to the increment over the core, relative to
   the increment's RMS. GelSlim fits a rigid motion; the affine terms also absorb the
   stretch that a stuck core undergoes when the pressure changes under it (the camera's
   perspective magnification, Poisson spreading), while the lag of a slipping periphery is
   not affine (even in position under shear, cubic under twist).
5. A real gel and its optical flow are not perfectly rigid even while stuck (the elastic
   layer smooths the field over a few millimetres; a narrow peg drags the gel beside it),
   and how much depends on the object. The stick **baseline** is therefore learned per
   grasp: the smallest residual of the first ``baseline_evaluations`` evaluations after
   zeroing (the first load increments, stuck by physics), capped at ``baseline_max``. The
   **score** is residual - baseline; those first evaluations only learn (score 0): a
   residual above the cap before anything was learned used to flag the first increment of
   a noisy, barely loaded contact.
6. Incipient slip: score >= ``incipient_score``; the verdict holds until the next judged
   increment or until the contact is unloaded (largest ``|t|`` below ``min_field_mm``).
   Gross slip: score >= ``gross_score`` (the slip front nears the core), and then the
   tangential field's RMS ("the load") stops growing for ``gross_confirm_s``; it ends when
   that RMS falls by ``release_fraction`` below its peak (the load is released).

Rejected after measurement: the residual of the whole field rather than of ``t`` (fires on
every tilt and grip change), a rigid rather than affine fit (fires on grip changes under a
narrow peg), judging every increment rather than loading ones (fires on tilts under a stuck
shear), a fixed residual threshold without the per-grasp baseline (precision about 0.5: the
stuck residual is 0.07 on a plate and up to 0.35 under a peg), the peripheral-to-central
ratio (about 0.8 under shear and 3 under torsion on the same plate) and the growth ratio of
the periphery (breaks under non-proportional loading). In a quasi-static simulation a
frozen field after a large score is all the field shows of gross slip; a hold just below
the friction limit looks the same.

**Re-zeroing.** After gross slip the object sits elsewhere on the gel, and the old reference
yields a spurious field. ``RezeroPolicy`` recommends a new reference only once the load has
been released (tangential RMS at most ``load_fraction`` of its peak during the slip) and the
whole field has been quiescent for ``quiet_s``; never while loaded, which would zero a load
into the reference. Its state is explicit (``RezeroState``) and its transition is a pure
function (``next_rezero_state``); the estimator applies it only when configured to.

Every array is allocated at construction; ``SlipDetector.update`` allocates only the
returned status.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from controller.tactile.field import VectorField, require_finite
from controller.tactile.nhhd import NHHDResult
from controller.tactile.settings import RezeroConfig, SlipConfig

# The affine fit has 6 parameters; with 2n values on n cells, n >= 6 leaves at least as many
# residual degrees of freedom as parameters (a core of 3 cells or fewer fits exactly).
MIN_CORE_CELLS = 6
# Timestamps are compared to durations with this slack, so that 0.04 s frames add up to 0.4 s.
_TIME_SLACK_S = 1e-9


@dataclass(frozen=True, slots=True)
class SlipStatus:
    """The detector's verdict for one frame.

    ``incipient``: part of the contact slips (also set during gross slip); ``gross``: the
    object slides as a whole; ``score``: the last judged increment's affine-fit residual
    above the grasp's stick baseline (dimensionless, 0 = as rigid as the stuck grasp);
    ``load_mm``: RMS over the grid of the field's divergence-free part, mm; ``change_mm``:
    the largest change of any cell of the whole field since the previous frame, mm.
    """

    incipient: bool
    gross: bool
    score: float
    load_mm: float
    change_mm: float


class SlipDetector:
    """Slip detection on a fixed grid (see the module docstring).

    ``x_mm`` (cols,) and ``y_mm`` (rows,) are the grid's cell centres in frame S. Feed it
    every frame with ``update``; ``reset`` forgets the history (call it with a new
    reference).
    """

    def __init__(self, config: SlipConfig, x_mm: np.ndarray, y_mm: np.ndarray) -> None:
        self.config = config
        self._x, self._y = np.meshgrid(x_mm, y_mm)
        shape = self._x.shape
        self._tu, self._tv = np.empty(shape), np.empty(shape)
        self._anchor_u, self._anchor_v = np.zeros(shape), np.zeros(shape)
        self._inc_u, self._inc_v = np.empty(shape), np.empty(shape)
        self._prev_u, self._prev_v = np.zeros(shape), np.zeros(shape)
        self._magnitude = np.empty(shape)
        self._core = np.empty(shape)
        self._wu, self._wv = np.empty(shape), np.empty(shape)
        self._fit = CoreFit(self._x, self._y)
        self.reset()

    def reset(self) -> None:
        """Forget the history: the next frame starts a new grasp (baseline relearned)."""
        self._anchor_u.fill(0.0)
        self._anchor_v.fill(0.0)
        self._have_previous = False
        self._evaluations = 0
        self._baseline = self.config.baseline_max
        self._score = 0.0
        self._incipient = False
        self._near_gross = False
        self._peak_load = 0.0
        self._growth_s = 0.0

    @property
    def baseline(self) -> float:
        """The grasp's stick residual (dimensionless); ``baseline_max`` until learned."""
        return self._baseline

    def update(self, field: VectorField, decomposition: NHHDResult, t_s: float) -> SlipStatus:
        """Judge the zeroed ``field`` (mm, frame S) of the frame at ``t_s`` seconds, given its
        NHHD ``decomposition`` (only the diverging part ``d`` is used)."""
        u, v = field.u_mm, field.v_mm
        if u.shape != self._x.shape or decomposition.d_u.shape != u.shape:
            raise ValueError(
                f"slip detector: expected fields of shape {self._x.shape}, got {u.shape} "
                f"(decomposition {decomposition.d_u.shape})"
            )
        require_finite("displacement field", u, v)
        change = self._frame_change(u, v)
        cfg = self.config
        tu = np.subtract(u, decomposition.d_u, out=self._tu)
        tv = np.subtract(v, decomposition.d_v, out=self._tv)
        magnitude = np.hypot(tu, tv, out=self._magnitude)
        largest = float(magnitude.max())
        load = math.sqrt((float(np.vdot(tu, tu)) + float(np.vdot(tv, tv))) / u.size)
        if largest < cfg.min_field_mm:
            # Unloaded: nothing can slip; increments count from here.
            np.copyto(self._anchor_u, tu)
            np.copyto(self._anchor_v, tv)
            self._score, self._incipient, self._near_gross = 0.0, False, False
            return SlipStatus(False, False, 0.0, load, change)
        inc_u = np.subtract(tu, self._anchor_u, out=self._inc_u)
        inc_v = np.subtract(tv, self._anchor_v, out=self._inc_v)
        np.hypot(inc_u, inc_v, out=self._wu)
        if float(self._wu.max()) >= cfg.min_increment_mm:
            self._evaluate(largest, load, t_s)
        gross = self._track_gross(load, t_s)
        return SlipStatus(self._incipient or gross, gross, self._score, load, change)

    def _frame_change(self, u: np.ndarray, v: np.ndarray) -> float:
        """Largest cell change of the whole field since the previous frame, mm."""
        change = 0.0
        if self._have_previous:
            np.subtract(u, self._prev_u, out=self._wu)
            np.subtract(v, self._prev_v, out=self._wv)
            change = float(np.hypot(self._wu, self._wv, out=self._wu).max())
        np.copyto(self._prev_u, u)
        np.copyto(self._prev_v, v)
        self._have_previous = True
        return change

    def _evaluate(self, largest: float, load: float, t_s: float) -> None:
        cfg = self.config
        np.greater_equal(self._magnitude, cfg.core_fraction * largest, out=self._core)
        if float(self._core.sum()) < MIN_CORE_CELLS:
            return  # an affine fit explains it exactly: no residual to judge
        fit = self._fit
        fit.set_weights(self._core)
        increment, residual = fit.motion(self._inc_u, self._inc_v)
        tangential, _ = fit.motion(self._tu, self._tv)
        np.copyto(self._anchor_u, self._tu)
        np.copyto(self._anchor_v, self._tv)
        if _cosine(increment, tangential) < cfg.loading_cosine:
            return
        if _norm(increment) < cfg.min_rigid_fraction * fit.rms(self._inc_u, self._inc_v):
            return
        self._evaluations += 1
        if self._evaluations <= cfg.baseline_evaluations:
            self._baseline = min(self._baseline, residual)
        self._score = residual - self._baseline
        if self._evaluations <= cfg.baseline_evaluations:
            self._score = 0.0  # the first loading increments are stuck by premise: learn only
        self._incipient = self._score >= cfg.incipient_score
        if self._score >= cfg.gross_score:
            if not self._near_gross:
                self._near_gross, self._peak_load, self._growth_s = True, load, t_s
        elif not self._incipient:
            self._near_gross = False

    def _track_gross(self, load: float, t_s: float) -> bool:
        """Gross slip: near-gross, and the load has not grown for ``gross_confirm_s``."""
        if not self._near_gross:
            return False
        cfg = self.config
        if load > self._peak_load * (1.0 + cfg.growth_tolerance):
            self._peak_load, self._growth_s = load, t_s
        elif load < self._peak_load * (1.0 - cfg.release_fraction):
            self._near_gross = False
            return False
        return t_s - self._growth_s >= cfg.gross_confirm_s - _TIME_SLACK_S


def _norm(a: tuple[float, float, float]) -> float:
    return math.sqrt(a[0] ** 2 + a[1] ** 2 + a[2] ** 2)


def _cosine(a: tuple[float, float, float], b: tuple[float, float, float]) -> float:
    norms = math.sqrt((a[0] ** 2 + a[1] ** 2 + a[2] ** 2) * (b[0] ** 2 + b[1] ** 2 + b[2] ** 2))
    return (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) / norms if norms > 0.0 else 0.0


class CoreFit:
    """Weighted least-squares motion fits over a set of cells (the contact core).

    ``x``, ``y``: cell positions (rows, cols), mm. ``set_weights(w)`` fixes the weights
    (w >= 0, e.g. a 0/1 core mask); ``motion(du, dv)`` then fits the field (du, dv) with an
    affine motion about the weighted centroid c:

        (du, dv) ~ t + A (p - c),  t = (t_x, t_y), A a 2 x 2 matrix

    (translation, rotation, uniform expansion and two stretches). Translation and the
    linear part are orthogonal under the weights, so the misfit energy is the field's
    weighted energy minus W |t|^2 and s^T C^-1 s for each component, with C the weighted
    covariance of the positions and s the weighted moments of the component.

    It returns the rigid part (t_x, t_y, omega * rho), with omega the least-squares rotation
    and rho the core's radius of gyration, so the three are all mm, and the relative residual
    sqrt(misfit / energy) in [0, 1] (0 for an affine motion or a zero field). Nothing is
    allocated but the returned tuples.
    """

    def __init__(self, x: np.ndarray, y: np.ndarray) -> None:
        self._x, self._y = x, y
        self._xx, self._yy, self._xy = x * x, y * y, x * y
        self._w = np.zeros(x.shape)
        self._wu, self._wv = np.empty(x.shape), np.empty(x.shape)
        self._scale2 = float((self._xx + self._yy).max()) + 1.0
        self.set_weights(np.ones(x.shape))

    def set_weights(self, weight: np.ndarray) -> None:
        w = self._w
        np.copyto(w, weight)
        total = float(w.sum())
        if total <= 0.0:
            raise ValueError("core fit: the weights must not all be zero")
        cx = float(np.vdot(w, self._x)) / total
        cy = float(np.vdot(w, self._y)) / total
        self._total, self._cx, self._cy = total, cx, cy
        self._cxx = max(float(np.vdot(w, self._xx)) - total * cx * cx, 0.0)
        self._cyy = max(float(np.vdot(w, self._yy)) - total * cy * cy, 0.0)
        self._cxy = float(np.vdot(w, self._xy)) - total * cx * cy

    def motion(self, du: np.ndarray, dv: np.ndarray) -> tuple[tuple[float, float, float], float]:
        total, cx, cy = self._total, self._cx, self._cy
        wu = np.multiply(self._w, du, out=self._wu)
        wv = np.multiply(self._w, dv, out=self._wv)
        energy = float(np.vdot(wu, du)) + float(np.vdot(wv, dv))
        sum_u, sum_v = float(wu.sum()), float(wv.sum())
        # Centred first moments: s_u = (sum w dx du, sum w dy du), s_v likewise.
        xu = float(np.vdot(self._x, wu)) - cx * sum_u
        yu = float(np.vdot(self._y, wu)) - cy * sum_u
        xv = float(np.vdot(self._x, wv)) - cx * sum_v
        yv = float(np.vdot(self._y, wv)) - cy * sum_v
        inertia = self._cxx + self._cyy
        tiny = 1e-12 * total * self._scale2
        rotation = (xv - yu) / math.sqrt(total * inertia) if inertia > tiny else 0.0
        rigid = (sum_u / total, sum_v / total, rotation)
        if energy <= 0.0:
            return rigid, 0.0
        explained = (sum_u * sum_u + sum_v * sum_v) / total
        explained += self._linear_energy(xu, yu) + self._linear_energy(xv, yv)
        return rigid, math.sqrt(max(energy - explained, 0.0) / energy)

    def rms(self, du: np.ndarray, dv: np.ndarray) -> float:
        """Weighted RMS of the field (du, dv) over the cells, in its units."""
        wu = np.multiply(self._w, du, out=self._wu)
        wv = np.multiply(self._w, dv, out=self._wv)
        return math.sqrt((float(np.vdot(wu, du)) + float(np.vdot(wv, dv))) / self._total)

    def _linear_energy(self, sx: float, sy: float) -> float:
        """s^T C^-1 s for the 2 x 2 position covariance C (pseudo-inverse when the core's
        cells are collinear, zero when it is a single cell)."""
        cxx, cyy, cxy = self._cxx, self._cyy, self._cxy
        trace = cxx + cyy
        if trace <= 1e-12 * self._total * self._scale2:
            return 0.0
        det = cxx * cyy - cxy * cxy
        if det > 1e-9 * trace * trace:
            return (cyy * sx * sx - 2.0 * cxy * sx * sy + cxx * sy * sy) / det
        # Rank one: C = trace e e^T, e along a non-zero column of C; C^+ = e e^T / trace.
        ex, ey = (cxx, cxy) if cxx >= cyy else (cxy, cyy)
        return (sx * ex + sy * ey) ** 2 / ((ex * ex + ey * ey) * trace)


RezeroPhase = Literal["armed", "slipped", "settled"]


@dataclass(frozen=True, slots=True)
class RezeroState:
    """The re-zero policy's whole state.

    ``phase``: ``armed`` (no gross slip since the last reference), ``slipped`` (gross slip
    seen; waiting for the load to be released and the field to settle), ``settled`` (a
    re-zero is recommended); ``peak_load_mm``: the largest tangential RMS during the slip;
    ``quiet_since_s``: since when the field has been released and quiet (None: it is not).
    """

    phase: RezeroPhase = "armed"
    peak_load_mm: float = 0.0
    quiet_since_s: float | None = None

    @property
    def recommended(self) -> bool:
        return self.phase == "settled"


def next_rezero_state(
    config: RezeroConfig, state: RezeroState, status: SlipStatus, t_s: float
) -> RezeroState:
    """The policy's transition for one frame at ``t_s`` seconds (a pure function).

    Gross slip (again) always leads to ``slipped``. From ``slipped`` or ``settled``, the
    phase is ``settled`` while the load has stayed released (``status.load_mm`` at most
    ``load_fraction`` of the peak) and the field quiet (``status.change_mm`` at most
    ``quiet_change_mm``) for ``quiet_s``; a load or a motion sends it back to ``slipped``.
    """
    if status.gross:
        peak = state.peak_load_mm if state.phase != "armed" else 0.0
        return RezeroState("slipped", max(peak, status.load_mm), None)
    if state.phase == "armed":
        return state
    released = status.load_mm <= config.load_fraction * state.peak_load_mm
    if not (released and status.change_mm <= config.quiet_change_mm):
        if state.phase == "slipped" and state.quiet_since_s is None:
            return state
        return RezeroState("slipped", state.peak_load_mm, None)
    since = t_s if state.quiet_since_s is None else state.quiet_since_s
    phase: RezeroPhase = "settled" if t_s - since >= config.quiet_s - _TIME_SLACK_S else "slipped"
    if phase == state.phase and since == state.quiet_since_s:
        return state
    return RezeroState(phase, state.peak_load_mm, since)


class RezeroPolicy:
    """Holds a ``RezeroState`` and advances it with ``next_rezero_state``; nothing else.

    ``update`` returns whether a re-zero is recommended now; ``reset`` returns to ``armed``
    (call it when a new reference is taken or the object is re-grasped).
    """

    def __init__(self, config: RezeroConfig) -> None:
        self.config = config
        self.state = RezeroState()

    def update(self, status: SlipStatus, t_s: float) -> bool:
        self.state = next_rezero_state(self.config, self.state, status, t_s)
        return self.state.recommended

    def reset(self) -> None:
        self.state = RezeroState()
