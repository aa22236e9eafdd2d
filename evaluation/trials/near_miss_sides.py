"""``python -m evaluation near_miss_sides``: at the sweep's near misses, do the tilt torques
name the side the opening lies on? Measured on recorded trials, with the true gel wrench and
with the estimate.

    python -m evaluation near_miss_sides OUT [OUT ...] [--jump-nm 0.0015]

Each OUT is a ``run_trials.py --records`` folder (or one trial's record). A near miss is a
moment of the sweep (``search.sweep``) with the tip above the board (less than
``ENTERED_M`` into the opening) and its face partly over the opening, off along one of the
opening's axes only: across the plug's thickness (the opening's short axis; off by more
than the clearance, within 0.3 mm along the width) or across its width (off along the long
axis, within 0.15 mm across it). There the board bears the face on the side away from the
opening, so the gel's torque on the plug should change by the press times that lever:
along -(u x z) in B, u the unit vector from the opening's centre to the tip. Each time the
torque about B's x and y changes by ``--jump-nm`` or more from the median of the frames
before (truth: the 0.05-0.2 s before; estimate: the 5 frames before, each at its capture
time), the cosine between the change and -(u x z) is taken; it ``agrees`` above 0.5 and
``opposes`` below -0.5. A torque that names the side agrees far more often than it
opposes. Writes nothing; a folder that is not a record: one line and exit code 2.
"""

from __future__ import annotations

import argparse
import json
from collections import defaultdict
from collections.abc import Iterable
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from controller.cli.support import ToolError, run_tool
from core.subcommands import job_prog
from evaluation.trials.entry_torque import ENTERED_M
from evaluation.trials.where_time_goes import record_folders

ALONG_M = {"thickness": 0.3e-3, "width": 0.15e-3}
"""How far off the near miss's other axis the tip may be (m)."""

SWEEP = "search.sweep"


def _side(offset_h: np.ndarray, opening: tuple[float, float], plug: tuple[float, float]):
    """("thickness" or "width", u in the hole's frame) for the tip's offset from the
    opening's centre in the hole's frame (m: x along the width, y across it), or (None,
    None) when its face is not partly over the opening along one axis."""
    dx, dy = offset_h
    (w_open, t_open), (w_plug, t_plug) = opening, plug
    clear_y, clear_x = (t_open - t_plug) / 2, (w_open - w_plug) / 2
    if abs(dx) < ALONG_M["thickness"] and clear_y < abs(dy) < (t_open + t_plug) / 2:
        return "thickness", np.array([0.0, np.sign(dy)])
    if abs(dy) < ALONG_M["width"] and clear_x < abs(dx) < (w_open + w_plug) / 2:
        return "width", np.array([np.sign(dx), 0.0])
    return None, None


def record_cosines(folder: Path, jump_nm: float) -> dict[tuple[str, str], list[float]]:
    """The cosines (see the module doc) of one trial record, by (signal, axis), for the
    torques' changes of ``jump_nm`` (N*m) or more."""
    try:
        config = json.loads((folder / "trial.json").read_text())["config"]
        ticks = [json.loads(line) for line in (folder / "ticks.jsonl").read_text().splitlines()]
        with np.load(folder / "truth.npz") as npz:
            truth = {k: npz[k] for k in npz.files}
        receptacle = config["scene"]["receptacle"]
        opening = (receptacle["width_m"], receptacle["height_m"])
        plug = (config["plug"]["width_m"], config["plug"]["thickness_m"])
        t_s, tip, depth = truth["t_s"], truth["tip_xyz_b"], truth["depth_m"]
        s2b = Rotation.from_quat(truth["plug_quat_b"][:, [1, 2, 3, 0]])
        yaw = float(truth["hole_yaw_rad"])
        centre = np.array([float(truth["hole_x_m"]), float(truth["hole_y_m"])])
        torque_b = s2b.apply(truth["gel_wrench_s"][:, 3:6])
        sweep_ticks = [k for k in ticks if k["stage"] == SWEEP]
    except (OSError, ValueError, KeyError, TypeError, IndexError) as exc:
        raise ToolError(f"{folder}: expected a trial record of the press spiral ({exc})") from None
    b2h = Rotation.from_euler("z", -yaw)
    out: dict[tuple[str, str], list[float]] = defaultdict(list)

    def add(signal: str, i: int, change_b: np.ndarray) -> None:
        size = float(np.linalg.norm(change_b[:2]))
        if size < jump_nm or depth[i] >= ENTERED_M:
            return
        offset_h = b2h.apply(np.r_[tip[i, :2] - centre, 0.0])[:2]
        axis, u_h = _side(offset_h, opening, plug)
        if axis is None:
            return
        u_b = Rotation.from_euler("z", yaw).apply(np.r_[u_h, 0.0])
        expected = -np.cross(u_b, [0.0, 0.0, 1.0])[:2]
        out[(signal, axis)].append(float(change_b[:2] @ expected / size))

    sweep_rows = np.searchsorted(t_s, [k["t_s"] for k in sweep_ticks])
    for i in sweep_rows[(sweep_rows >= 20) & (sweep_rows < len(t_s))]:
        base = np.median(torque_b[i - 20 : i - 5], axis=0)
        add("truth", int(i), torque_b[i] - base)
    frames, last = [], None
    for k in sweep_ticks:
        if k.get("estimate_t_s") in (None, last):
            continue
        last = k["estimate_t_s"]
        row = int(min(np.searchsorted(t_s, last), len(t_s) - 1))
        e = k["estimate"]
        frames.append((row, s2b[row].apply([e["tau_x"], e["tau_y"], e["tau_z"]])))
    for j in range(5, len(frames)):
        row, tau_b = frames[j]
        base = np.median([f[1] for f in frames[j - 5 : j]], axis=0)
        add("estimate", row, tau_b - base)
    return out


def report(folders: Iterable[Path], jump_nm: float) -> str:
    """The table over the records in ``folders`` (see the module doc)."""
    cosines: dict[tuple[str, str], list[float]] = defaultdict(list)
    records = [r for f in folders for r in record_folders(f)]
    for record in records:
        for key, values in record_cosines(record, jump_nm).items():
            cosines[key] += values
    lines = [
        f"{len(records)} records; changes of {jump_nm * 1e3:g} mN*m or more in the sweep",
        "| signal | face over the opening across | changes | mean cosine | agree | oppose |",
        "|---|---|---:|---:|---:|---:|",
    ]
    for signal in ("truth", "estimate"):
        for axis in ("thickness", "width"):
            v = np.array(cosines.get((signal, axis), []))
            if not v.size:
                lines.append(f"| {signal} | {axis} | 0 | – | – | – |")
                continue
            lines.append(
                f"| {signal} | {axis} | {v.size} | {v.mean():+.2f} | "
                f"{np.count_nonzero(v > 0.5)} | {np.count_nonzero(v < -0.5)} |"
            )
    return "\n".join(lines)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog=job_prog("near_miss_sides"), description=__doc__.splitlines()[0]
    )
    parser.add_argument("out", nargs="+", type=Path, help="run_trials --records folders")
    parser.add_argument(
        "--jump-nm", type=float, default=0.0015, help="the smallest change counted (N*m)"
    )
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)

    def run() -> int:
        if not args.jump_nm > 0:
            raise ToolError(f"--jump-nm {args.jump_nm}: expected a positive torque (N*m)")
        print(report(args.out, args.jump_nm))
        return 0

    return run_tool("near_miss_sides", run)
