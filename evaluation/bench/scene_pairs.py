"""The insertion scene's benchmark against another checkout in the same run: paired runs,
one seed at a time, each in a fresh process, the two sides alternating.

A speed-up measured as "before" on one day and "after" on another mostly measures the
machine's load, which moves CPU seconds too (other jobs share the caches and the memory
bus). Here each seed runs ``python -m evaluation bench_insertion_scene --runs 1 --seed S`` in this
checkout and in the other one, back to back (this side first on even seeds, the other
first on odd ones, so a drift in the load falls on both alike), each in its own process
(so both pay the same first-run costs: imports are outside the timed part, the estimator's
per-process constants inside it). The other checkout runs its own virtualenv's Python
(``CHECKOUT/.venv/bin/python``, this one's if it has none) and its own benchmark (a checkout
from before ``python -m evaluation``: its ``scripts/bench_insertion_scene.py``), so it must
print the same table row: ``| seed | sim s | wall s | x real time | CPU s | x per CPU s |
frames | depth mm |``. Reported per seed: both sides' speed per CPU second and per wall
second and the ratio this / other per CPU second; then the medians, the median of the
ratios, and the load average before and after.
"""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from controller.cli.support import ToolError, one_line

TOOLS = Path("evaluation") / "tools.py"
TOOL = ["-m", "evaluation", "bench_insertion_scene"]
"""How a checkout with ``TOOLS`` runs the benchmark (its Python's arguments, in the checkout)."""
SCRIPT = Path("scripts") / "bench_insertion_scene.py"
"""The benchmark's script in a checkout from before ``TOOLS``."""
ROOT = Path(__file__).resolve().parents[2]


@dataclass(frozen=True)
class SideRun:
    """One run's row of the benchmark's table: simulated s, wall s, CPU s, frames, depth m."""

    sim_s: float
    wall_s: float
    cpu_s: float
    frames: int
    depth_m: float

    @property
    def speed_x(self) -> float:
        """Simulated seconds per wall second."""
        return self.sim_s / self.wall_s

    @property
    def cpu_speed_x(self) -> float:
        """Simulated seconds per CPU second of the run's process."""
        return self.sim_s / self.cpu_s


def checkout_python(checkout: Path) -> str:
    """The Python that runs ``checkout``'s benchmark: its virtualenv's, else this one."""
    own = checkout / ".venv" / "bin" / "python"
    return str(own) if own.is_file() else sys.executable


def benchmark_arguments(checkout: Path) -> list[str] | None:
    """The arguments of ``checkout``'s Python that run its benchmark (in ``checkout``), or
    None if it has none."""
    if (checkout / SCRIPT).is_file():
        return [str(checkout / SCRIPT)]
    if (checkout / TOOLS).is_file():
        return list(TOOL)
    return None


def check_checkout(checkout: Path) -> Path:
    """``checkout`` resolved; ToolError unless it holds the benchmark."""
    if benchmark_arguments(checkout) is None:
        raise ToolError(
            f"--against '{checkout}': no {SCRIPT} there, nor {TOOLS}; expected the root of "
            "another checkout of this project (e.g. a git worktree at the base commit)"
        )
    return checkout.resolve()


def parse_row(output: str, seed: int) -> SideRun:
    """The table row of ``seed`` in the benchmark's output; ValueError if there is none."""
    for line in output.splitlines():
        cells = [cell.strip() for cell in line.strip().strip("|").split("|")]
        if len(cells) == 8 and cells[0] == str(seed):
            sim_s, wall_s, _, cpu_s, _, frames, depth_mm = cells[1:]
            return SideRun(
                float(sim_s), float(wall_s), float(cpu_s), int(frames), float(depth_mm) / 1e3
            )
    raise ValueError(f"no table row for seed {seed}")


def run_side(checkout: Path, seed: int, options: Sequence[str]) -> SideRun:
    """One timed run of ``seed`` by ``checkout``'s benchmark in a fresh process (``options``:
    the task, ``--no-estimate``, overrides); ToolError naming the checkout if it fails."""
    arguments = benchmark_arguments(checkout) or [str(checkout / SCRIPT)]
    command = [checkout_python(checkout), *arguments, "--runs", "1", "--seed"]
    done = subprocess.run(
        [*command, str(seed), *options], cwd=checkout, capture_output=True, text=True
    )
    if done.returncode != 0:
        last = (done.stderr.strip().splitlines() or ["(no message)"])[-1]
        raise ToolError(
            f"the benchmark in '{checkout}' failed on seed {seed} (exit {done.returncode}): "
            f"{one_line(last)}"
        )
    try:
        return parse_row(done.stdout, seed)
    except ValueError as exc:
        raise ToolError(f"the benchmark in '{checkout}' printed {exc}") from None


def paired_runs(
    other: Path, seeds: range, options: Sequence[str], this: Path = ROOT
) -> Iterator[tuple[int, SideRun, SideRun]]:
    """(seed, this side's run, the other's) per seed as each pair finishes, the order
    alternating (module docstring)."""
    for seed in seeds:
        order = (this, other) if seed % 2 == 0 else (other, this)
        first, second = (run_side(checkout, seed, options) for checkout in order)
        yield (seed, first, second) if seed % 2 == 0 else (seed, second, first)


def print_pairs(other: Path, seeds: range, options: Sequence[str]) -> None:
    """Run and print the paired comparison (module docstring)."""
    load_before = os.getloadavg()
    print(f"This checkout: {ROOT}; the other: {other}.\n")
    print("| seed | this x per CPU s | other x per CPU s | ratio | this x real time | "
          "other x real time | frames | depth mm (this / other) |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|")
    pairs = []
    for seed, mine, theirs in paired_runs(other, seeds, options):
        pairs.append((mine, theirs))
        frames = f"{mine.frames}" + ("" if mine.frames == theirs.frames else f" / {theirs.frames}")
        print(
            f"| {seed} | {mine.cpu_speed_x:.1f} | {theirs.cpu_speed_x:.1f} | "
            f"{mine.cpu_speed_x / theirs.cpu_speed_x:.2f} | {mine.speed_x:.1f} | "
            f"{theirs.speed_x:.1f} | {frames} | {mine.depth_m * 1e3:.2f} / "
            f"{theirs.depth_m * 1e3:.2f} |",
            flush=True,
        )
    load_after = os.getloadavg()
    ratio = float(np.median([m.cpu_speed_x / t.cpu_speed_x for m, t in pairs]))
    print(
        f"\nMedians: this {np.median([m.cpu_speed_x for m, _ in pairs]):.1f}x, the other "
        f"{np.median([t.cpu_speed_x for _, t in pairs]):.1f}x per CPU second (this "
        f"{np.median([m.speed_x for m, _ in pairs]):.1f}x, the other "
        f"{np.median([t.speed_x for _, t in pairs]):.1f}x per wall second); median paired "
        f"ratio {ratio:.2f}. Load average (1, 5, 15 min) before "
        f"{', '.join(f'{v:.1f}' for v in load_before)}, after "
        f"{', '.join(f'{v:.1f}' for v in load_after)}."
    )
