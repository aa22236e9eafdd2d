"""Near misses of the press-spiral machine on touch: the tilt torques' jump that says the
plug's face crossed the opening without dropping in, and the retrace that goes back over it.

Why: the plug drops in only where the tip crosses the opening within the clearance across
its path (USB-C: 2.56 mm for 2.4 mm, about +-0.08 mm), and the spiral's rings lie a pitch
apart (0.3 mm): a ring that passes the opening 0.1-0.2 mm off lets part of the face hang
over it. The board then bears the face on one edge and the opening's rim catches the other;
the tilt torques (about T x and T y) jump for a frame or two, while the axial load does not
drop (the face still rests on the board), so no probe starts. Across the plug's thickness,
where the clearance is, the jump's direction does not name the side the opening lies on,
not even in the true wrench; across its width it does about 3 times in 4 (``python -m
evaluation near_miss_sides``, docs/BENCHMARKS.md). So the retrace takes the ring that the
pattern skips, half a pitch outward, or with ``toward_side`` the one half a pitch to the
side the jump names (``side_named_b``), outward or inward.

**Detection** (``NearMissDetector``): each new frame's torques about T x and T y during the
sweep, against the median of the ``median_frames`` frames before it in the same sweep (the
friction of the drag is in the baseline); a jump of ``tilt_jump_nm`` or more is a near miss,
described at the frame's capture time. The side it names: the board bears the face away
from the opening, so the torque (in B) changes along -(u x z_B), u the unit vector from the
opening to the tip; the opening lies along -u.

**Retrace** (SEARCH's ``retrace`` sub-stage, spiral_search.py): once the sweep has gone
``ahead_m`` past where the tip was at that time without a catch (the face overlaps the
opening's end before the same ring brings the tip over it: a retrace at once would cut that
catch short), the pattern goes back to ``back_m`` before it and sweeps to ``ahead_m`` after
it, with the pattern's radius ``outward_m`` larger (the ring halfway to the next); the
sweep then resumes along its own ring where it had reached, its baseline taken anew. A load
drop on the way is a probe as in the sweep. At most ``per_pass`` retraces a pass (a rim
that chatters costs no more than that), from pass ``from_pass`` on.

Off in the shipped tasks: on the tuning seeds every form of the retrace, toward the named
side too, cost the first pass's catches more time than its own catches saved
(docs/BENCHMARKS.md, "Near misses felt and retraced").
"""

from __future__ import annotations

from collections import deque

import numpy as np
from scipy.spatial.transform import Rotation

from core.config import Config, config_dataclass, number


@config_dataclass
class NearMissSettings(Config):
    """The task's ``touch_spiral.near_miss:`` (see the module doc): ``enabled``;
    ``tilt_jump_nm``: the jump of the tilt torques (about T x and T y, N*m) that marks a near
    miss; ``median_frames``: the frames before it whose median is the baseline;
    ``back_m``, ``ahead_m``: the retrace sweeps from this far before the near miss's place
    to this far after it (m of path);
    ``outward_m``: the retrace's ring this far outside the
    pattern's (m), or inside it where ``toward_side`` and the jump names the inside;
    ``per_pass``: the most retraces in one pass; ``from_pass``: the first pass (0: the first)
    whose near misses are retraced."""

    enabled: bool = False
    tilt_jump_nm: float = number(1e-5, 0.1, default=0.0015)
    median_frames: int = number(2, 50, default=5)
    back_m: float = number(0.0, 0.02, default=0.002)
    ahead_m: float = number(0.0, 0.02, default=0.002)
    outward_m: float = number(0.0, 0.002, default=0.00015)
    per_pass: int = number(0, 100, default=3)
    from_pass: int = number(0, 100, default=0)
    toward_side: bool = False


class NearMissDetector:
    """The tilt torques' jump over the sweep's baseline (see the module doc)."""

    def __init__(self, settings: NearMissSettings) -> None:
        self.settings = settings
        self._tilts: deque[np.ndarray] = deque(maxlen=settings.median_frames)
        self._frame_t_s = -np.inf

    def reset(self) -> None:
        """A new sweep: no baseline yet."""
        self._tilts.clear()

    def jump(self, torque_t: np.ndarray | None, frame_t_s: float) -> np.ndarray | None:
        """The change of the tilt torques (N*m, about T x and T y) if the frame captured at
        ``frame_t_s`` (s), with torques ``torque_t`` (N*m, in T), is a near miss, else None;
        each frame is taken once, and a near miss's frame does not join the baseline."""
        if torque_t is None or frame_t_s <= self._frame_t_s:
            return None
        self._frame_t_s = frame_t_s
        tilt = np.asarray(torque_t[:2], dtype=float)
        if len(self._tilts) == self._tilts.maxlen:
            change = tilt - np.median(self._tilts, axis=0)
            if float(np.linalg.norm(change)) >= self.settings.tilt_jump_nm:
                return change
        self._tilts.append(tilt)
        return None


def side_named_b(jump_t: np.ndarray, t2b: Rotation) -> np.ndarray:
    """The unit vector in B's x-y plane toward the side where a near miss's ``jump_t`` (the
    tilt torques' change about T x and T y, N*m) puts the opening, the TCP turned by ``t2b``
    (T2B): the torque changes along -(u x z_B), so the opening, along -u, lies along
    (-dtau_y, dtau_x) (module doc)."""
    d_tau = t2b.apply([float(jump_t[0]), float(jump_t[1]), 0.0])
    toward = np.array([-d_tau[1], d_tau[0]])
    return toward / max(float(np.linalg.norm(toward)), 1e-12)
