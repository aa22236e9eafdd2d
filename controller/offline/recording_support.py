"""Without the open gel: where the contact is, from the whole recording.

The default's tilt is the moment of the divergence about the contact's support measured
from the closing press against the open gel (``grasp_centroid``, docs/ARCHITECTURE.md, "Under
pushing"); about that support's centre c a swinging grip pressure drops out. A recording
without open frames has no closing press, and the fallback (the centroid midpoint on 4 x 4
blocks) leaks the push into the tilt. Offline the tool sees every frame, and every frame's
divergence d_t (on the field grid, the curl-free part's) is zero off the contact but for the
camera noise: on the contact it is a_t + b_t (x - c) (a press, a tilt). So per cell i:

    P_i = mean_t d_t,i^2                       its power over the recording
    C_i = mean_t (d_t+1,i - d_t,i)^2 / 2       its frame-to-frame change: the noise power,
                                               plus the motion's share where the gel moves
    N   = the 25th percentile of C over the cells: the noise floor (the camera noise is
          about the same everywhere; most cells are off the contact, and motion only adds)
    e_i = max(P_i / N - 1, 0)                  the excess power in noise units

and the support is ``dipole.grasp_support`` of e (smoothstep of e relative to its largest
value, 0 at or below 20%, 1 from 70%: the open gel's rule) with its centroid, provided the
contact moved the gel clearly more than noise alone would over the recording's T frames:

    V_i = var_t d_t,i                          the cell's change over the recording (the
                                               reference's own noise, a constant, drops out)
    m   = max_i (V_i / N - 1) / sqrt(2 / (T - 1))

in units of the relative spread of a noise power measured over T frames, must reach
``MOTION_SIGNIFICANCE``. Noise alone (the real-gel check's captures with the field zero,
40 and 160 frames) reaches m of 4.5-11 on the backgrounds and 13-31 on the marker gels; its
P_i / N, which holds the reference's noise, reaches e of 1.8-5.7 on the backgrounds, as high
as a weak tilt's. Below that the support would weigh the cells where the reference happened
to be noisiest, and the tilt is taken on the whole grid instead (the 4 x 4 moment, None
here; docs/ARCHITECTURE.md, "Without open frames", item 4), through the paper's temporal
filter (EMA weight ``NOISE_EMA_ALPHA``, item 5): at the noise, averaging over frames is what
is left to gain. Taken against
the noise, a weak tilt across a contact's narrow side still finds the contact, where the
relative power alone also weighs the cells off it; taken against each cell's own change,
a low-noise gel (markers) whose motion dominates the changes spreads the support over the
whole grid (on tuning seed 100 of the real-gel check, tilt alone: R^2 0.76-0.96 with N,
0.46-0.86 with the power alone; the rendered GelSight marker recordings: 91% sign agreement
with C_i, 100% with N). A tilt alone is about antisymmetric about c and a push about
uniform, so both put c at the contact's centre.

``recording_fallback``: after a first pass over a recording without ``--open`` (the
configured estimator, its field divergences collected), the estimator to estimate it again
with, the record of that choice (``OUT.fallback.json``) and its one-line message. The
no-contact gate stays unless the first pass's gate never saw a press from the open gel
(its peak statistic below ``PRESS_RATIO`` times its threshold): the recording was then zeroed in
the grasp, and the gate would only cut into its tilt. Such a recording whose change is not
clearly above the noise (no support) is estimated again on the whole grid, without the gate,
through the paper's EMA.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from controller.tactile import TactileEstimator
from controller.tactile.dipole import GraspSupport, grasp_support
from controller.tactile.estimator import GridFlowFactory
from controller.tactile.field import require_finite
from controller.tactile.flow import make_grid_flow

# A recording whose no-contact gate never reached PRESS_RATIO times its threshold saw no press
# from the open gel (hundreds of times the threshold): it was zeroed in the grasp (or never
# touched), and the gate would only cut into its tilt (docs/ARCHITECTURE.md, "Without open
# frames").
PRESS_RATIO = 10.0
SUPPORT_REASON = "no open gel given: the contact's support taken from the whole recording"
UNGATED_REASON = "no open gel given and no press from the open gel in the recording"
WHOLE_GRID_REASON = (
    "no contact's support in the recording (its change not clearly above the camera noise, or "
    "too few frames): the tilt on the whole grid, averaged over frames as the paper does"
)
# The weight of the newest field in the temporal filter of a recording at the noise: the
# paper's EMA (configs/estimators/paper.yaml, the authors' value, not tuned here). On the
# tuning sequences taken on the whole grid it lifts R^2 on 15 of 16 (docs/ARCHITECTURE.md,
# "Without open frames", item 5).
NOISE_EMA_ALPHA = 0.6
# Fewer frames leave too few frame-to-frame changes to tell the noise from the contact.
MIN_FRAMES = 8
# The percentile of the cells' frame-to-frame change taken as the noise floor.
NOISE_PERCENTILE = 25.0
# The largest change over the recording, in units of a noise power's relative spread over
# its frames, below which no support is taken (module docstring). Set on the tilt-alone
# sequences of tuning seeds 100-103 and 200-225 of the real-gel check's varied contacts: the
# middle of 13-19, where the fewest fall short of `paper` (docs/ARCHITECTURE.md).
MOTION_SIGNIFICANCE = 16.0


def recording_support(
    divergences: Sequence[np.ndarray] | np.ndarray, x_mm: np.ndarray, y_mm: np.ndarray
) -> GraspSupport | None:
    """The contact's support (module docstring) from the field divergences ``divergences``
    (frames, rows, cols), dimensionless, on the grid ``x_mm`` (cols,) x ``y_mm`` (rows,), mm in
    frame S; None with fewer than ``MIN_FRAMES`` frames, or no cell above its noise, or no
    cell's change over the recording clearly above what the noise alone reaches."""
    stack = np.asarray(divergences, float)
    if stack.ndim != 3 or stack.shape[1:] != (y_mm.size, x_mm.size):
        raise ValueError(
            f"divergences must be (frames, {y_mm.size}, {x_mm.size}), got {stack.shape}"
        )
    require_finite("divergences", stack)
    if len(stack) < MIN_FRAMES:
        return None
    power = np.square(stack).mean(axis=0)
    change = np.square(np.diff(stack, axis=0)).mean(axis=0) / 2.0
    noise = float(np.percentile(change, NOISE_PERCENTILE))
    if not noise > 0.0:  # a still recording: no noise to measure against
        return None
    if motion_significance(stack, noise) < MOTION_SIGNIFICANCE:
        return None
    excess = np.maximum(power / noise - 1.0, 0.0)
    return grasp_support(excess, x_mm, y_mm) if float(excess.max()) > 0.0 else None


def motion_significance(stack: np.ndarray, noise: float) -> float:
    """m of the module docstring: the largest variance over the frames of ``stack`` (frames,
    rows, cols) per cell, in excess of the noise power ``noise`` (same units squared) and
    relative to it, over a noise power's relative spread over that many frames."""
    spread = np.sqrt(2.0 / (len(stack) - 1))
    return float((stack.var(axis=0).max() / noise - 1.0) / spread)


@dataclass(frozen=True)
class FallbackChoice:
    """What the offline tool estimates a recording again with: ``estimator`` (its reference
    not set), ``record`` (the sidecar's content) and ``message`` (its one warning line)."""

    estimator: TactileEstimator
    record: dict
    message: str


def uses_recording(estimator: TactileEstimator, open_given: bool) -> bool:
    """Whether a first pass of ``estimator`` over a recording should collect its divergences
    for ``recording_fallback``: no open gel given, and the tilt taken about the grasp's
    support (``grasp_centroid``)."""
    return not open_given and estimator.config.dipole_origin == "grasp_centroid"


def recording_fallback(
    first: TactileEstimator,
    divergences: Sequence[np.ndarray],
    open_given: bool,
    flow: GridFlowFactory = make_grid_flow,
) -> FallbackChoice | None:
    """After a first pass of ``first`` over a recording, with its ``field_divergence`` per
    frame in ``divergences``: the estimator to estimate it again with (module docstring),
    or None to keep the first pass (the open gel was given, or the configuration does not
    take the tilt about the grasp's support, or neither a support nor the gate's rule
    applies). ``flow``: the new estimator's flow hook (``first``'s, for an experiment)."""
    config = first.config
    if not uses_recording(first, open_given):
        return None
    ungated = first.noise_gated and first.noise_gate_peak < PRESS_RATIO
    support = None
    if divergences:
        field = first.field
        support = recording_support(divergences, field.x_mm, field.y_mm)
    if support is None and not ungated:
        return None
    if ungated:
        config = replace(config, noise_gate=None)
    if support is None:  # at the noise: at least the paper's averaging over frames
        config = replace(config, ema_alpha=min(config.ema_alpha, NOISE_EMA_ALPHA))
    estimator = TactileEstimator(
        config,
        first.profile,
        first.calibration,
        config_name=first.config_name,
        flow=flow,
    )
    record: dict = {"estimator": first.config_name}
    reasons = []
    if support is not None:
        estimator.set_contact_support(support)
        record["contact_support"] = {
            "centre_mm": [round(v, 4) for v in support.centre_mm],
            "weights": np.round(support.weights, 4).tolist(),
        }
        reasons.append(SUPPORT_REASON)
    else:
        record["contact_support"] = None
        record["ema_alpha"] = config.ema_alpha
        reasons.append(WHOLE_GRID_REASON)
    if ungated:
        record["noise_gate"] = None
        reasons.append(UNGATED_REASON + ": without the no-contact gate")
    record["reason"] = "; ".join(reasons)
    return FallbackChoice(estimator, record, record["reason"])
