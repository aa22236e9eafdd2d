"""The insertion scene's ground truth: what the simulator knows and the controller never
sees (it goes to the run's record, e.g. for the summary plot and the oracle controller).

One row every ``1 / truth_rate_hz`` s of simulated time:

* ``t_s``: time on the scene's clock, s;
* ``gel_wrench_s`` (6): the wrench the sensing finger's gel exerts on the plug, in S about
  S's origin (fx, fy, fz N; tau_x, tau_y, tau_z N*m): the convention of the gel model's
  ``Wrench`` and of the tactile estimate (docs/ARCHITECTURE.md); the wrench the plug puts
  on the finger is its negative;
* ``wrist_wrench_t`` (6): the wrench the compliant wrist's springs exert on the gripper,
  along the gripper's axes (T's when at rest) at the wrist's pivot (N, N*m);
* ``tip_xyz_b`` (3): the plug's tip (its axis at the tip) in B, m; ``plug_quat_b`` (4):
  the plug's orientation, S2B as (w, x, y, z);
* ``depth_m``: how far the tip is below the board surface (the hole's z), m (negative
  above it);
* ``contact_force_n``: the largest, over the physics steps since the previous row, of the
  sum of the normal forces of the plug's contacts with the board and the receptacle, N
  (a wedged plug's squeeze counts once per wall);
* ``insertion_force_n``: the largest, over the same steps, of the net contact force on the
  plug along the true hole's axis (out of the board), N: the force that resists the
  insertion, which the connectors' specifications limit (0 without contact).

``hole`` is the true hole pose in B; ``hole_nominal`` the one the task file gives.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from core.task_geometry import HolePose

COLUMNS = {
    "t_s": 1,
    "gel_wrench_s": 6,
    "wrist_wrench_t": 6,
    "tip_xyz_b": 3,
    "plug_quat_b": 4,
    "depth_m": 1,
    "contact_force_n": 1,
    "insertion_force_n": 1,
}
TRUTH_WIDTH = sum(COLUMNS.values())


@dataclass
class TruthLog:
    """Rows of ground truth (see the module docstring), appended by the scene."""

    hole: HolePose
    hole_nominal: HolePose
    _rows: list[np.ndarray] = field(default_factory=list, repr=False)

    def append(self, row: np.ndarray) -> None:
        """One row of ``sum(COLUMNS.values())`` numbers in ``COLUMNS`` order."""
        if row.shape != (TRUTH_WIDTH,):
            raise ValueError(f"row: expected shape ({TRUTH_WIDTH},), got {row.shape}")
        self._rows.append(row)

    def __len__(self) -> int:
        return len(self._rows)

    def rows_since(self, start: int) -> list[np.ndarray]:
        """The rows from index ``start`` on, each in ``COLUMNS`` order (a recorder reads
        what is new since its last read)."""
        return self._rows[start:]

    def arrays(self) -> dict[str, np.ndarray]:
        """Every column as an array: (n,) for one number, (n, k) for k."""
        table = np.array(self._rows).reshape(-1, TRUTH_WIDTH)
        out, start = {}, 0
        for name, width in COLUMNS.items():
            block = table[:, start : start + width]
            out[name] = block[:, 0] if width == 1 else block
            start += width
        return out

    @property
    def max_contact_force_n(self) -> float:
        """The largest contact force of the whole run so far, N (0 with no rows)."""
        return float(max((r[-2] for r in self._rows), default=0.0))
