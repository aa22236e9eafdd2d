"""Where a simulated insertion spends its CPU, by part of the scene, two ways.

``part_clock()``: timers on the CPU-time clock (``time.process_time``) around each part's
entry points (``ENTRY_POINTS``, patched for the duration of the ``with`` block), each part's
time exclusive of the parts it calls (a frame's render calls the gel solve, which steps the
physics). About a microsecond per call: the split of an unprofiled run.

``profile_call()`` and ``part_times()``: a ``cProfile`` profile (on the same clock) whose
functions are attributed to the part whose code they are, and library code (NumPy, OpenCV,
SciPy, MuJoCo, built-ins) to the part that called it, in proportion to the time each caller
spent in it: what inside a part costs.

The parts (``PARTS``, matched on the function's file, first match wins): the estimator
(controller/tactile/), the physics (the MuJoCo stepping, drivers/sim/scenes/insertion/
physics.py, and ``mujoco`` itself), the gel solve (drivers/sim/gel/ and the coupling), the
rendering (drivers/sim/render/ and the camera twin), the arm twin (its kinematics and the
envelope's clamps, core/), the gripper twin, and the loop (the world's glue, the clock and
the benchmark's own ticks); whatever none of them reaches is "other".

The profiler's own cost falls on every Python call, so it inflates the Python-heavy parts
(the arm twin most, several times over, the physics' step loop next) against those that
spend their time inside one library call (the estimator's and the renderer's OpenCV): its
shares say what costs inside a part, ``part_clock`` how the parts compare.
"""

from __future__ import annotations

import cProfile
import pstats
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

from controller.tactile.estimator import TactileEstimator
from drivers.sim.render.gel_renderer import GelRenderer
from drivers.sim.scenes.insertion.coupling import GelCoupling
from drivers.sim.scenes.insertion.physics import InsertionPhysics
from drivers.sim.twins.arm import SimArm
from drivers.sim.twins.gripper import SimGripper

# (part, file path fragments): a function belongs to the first part one of whose fragments
# is in its file's path ("/" separated)
PARTS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("estimator", ("controller/tactile/",)),
    ("physics", ("drivers/sim/scenes/insertion/physics.py", "mujoco")),
    ("gel solve", ("drivers/sim/gel/", "drivers/sim/scenes/insertion/coupling.py")),
    ("rendering", ("drivers/sim/render/", "drivers/sim/twins/tactile.py")),
    (
        "arm twin",
        (
            "drivers/sim/twins/arm.py",
            "drivers/sim/twins/tcp_motion.py",
            "drivers/arm/",
            "core/envelope.py",
            "core/spatial.py",
            "core/quaternion.py",
        ),
    ),
    ("gripper twin", ("drivers/sim/twins/gripper.py",)),
    ("loop", ("drivers/sim/scenes/", "core/clock.py", "evaluation/bench/insertion_scene.py")),
)
OTHER = "other"

# (class, method, part): the calls through which the scene's parts are entered in a run
ENTRY_POINTS: tuple[tuple[type, str, str], ...] = (
    (TactileEstimator, "push", "estimator"),
    (TactileEstimator, "rezero", "estimator"),
    (TactileEstimator, "capture_open", "estimator"),
    (InsertionPhysics, "step_to", "physics"),
    (GelCoupling, "__call__", "gel solve"),
    (GelRenderer, "render", "rendering"),
    (SimArm, "read_status", "arm twin"),
    (SimArm, "servo_pose", "arm twin"),
    (SimGripper, "read_status", "gripper twin"),
    (SimGripper, "move", "gripper twin"),
    (SimGripper, "activate", "gripper twin"),
)

# A function in pstats: (file, line, name); built-ins have file "~".
Function = tuple[str, int, str]


@dataclass(frozen=True)
class PartTime:
    """One part's CPU seconds in the profile and its share of the profile's total."""

    part: str
    seconds: float
    share: float


@contextmanager
def part_clock(
    entry_points: tuple[tuple[type, str, str], ...] = ENTRY_POINTS,
) -> Iterator[dict[str, float]]:
    """Within the block, the CPU seconds spent in each part (through ``entry_points``: class,
    method, part), exclusive of the parts it called, accumulate in the dictionary yielded
    (part -> seconds)."""
    seconds: dict[str, float] = {}
    nested: list[float] = []  # per open entry: the time its nested entries took

    def timer(original: Callable[..., Any], part: str) -> Callable[..., Any]:
        def timed(*args: Any, **kwargs: Any) -> Any:
            start = time.process_time()
            nested.append(0.0)
            try:
                return original(*args, **kwargs)
            finally:
                took = time.process_time() - start
                seconds[part] = seconds.get(part, 0.0) + took - nested.pop()
                if nested:
                    nested[-1] += took

        return timed

    originals = [(owner, name, owner.__dict__[name]) for owner, name, _ in entry_points]
    for owner, name, part in entry_points:
        setattr(owner, name, timer(owner.__dict__[name], part))
    try:
        yield seconds
    finally:
        for owner, name, original in originals:
            setattr(owner, name, original)


def profile_call(call: Callable[[], object]) -> pstats.Stats:
    """Run ``call()`` under ``cProfile`` on the CPU-time clock; its statistics."""
    profiler = cProfile.Profile(time.process_time)
    profiler.enable()
    try:
        call()
    finally:
        profiler.disable()
    return pstats.Stats(profiler)


def part_of_file(path: str) -> str | None:
    """The part whose code ``path`` is (``PARTS``), None for library code."""
    path = path.replace("\\", "/")
    for part, fragments in PARTS:
        if any(fragment in path for fragment in fragments):
            return part
    return None


def part_times(stats: pstats.Stats) -> list[PartTime]:
    """Every part's exclusive CPU seconds in ``stats`` (module docstring), largest first;
    the shares add up to 1."""
    table = stats.stats  # type: ignore[attr-defined]  # pstats' documented raw table
    shares: dict[Function, dict[str, float]] = {}

    def parts_of(function: Function, visiting: frozenset[Function]) -> dict[str, float]:
        """The parts ``function``'s own time belongs to, as fractions adding up to 1 (a
        caller already on the path, a recursion, is left out)."""
        if function in shares:
            return shares[function]
        own = part_of_file(function[0])
        if own is not None:
            result = {own: 1.0}
        else:
            callers = {
                caller: timing
                for caller, timing in table[function][4].items()
                if caller not in visiting and caller in table
            }
            # weight each caller by the time the function spent for it (by the calls if
            # the clock saw none)
            weights = {caller: timing[2] for caller, timing in callers.items()}
            if not any(weights.values()):
                weights = {caller: float(timing[1]) for caller, timing in callers.items()}
            total = sum(weights.values())
            result = {}
            if total > 0:
                for caller, weight in weights.items():
                    for part, fraction in parts_of(caller, visiting | {function}).items():
                        result[part] = result.get(part, 0.0) + fraction * weight / total
            if not result:
                result = {OTHER: 1.0}
        shares[function] = result
        return result

    seconds: dict[str, float] = {}
    for function, (_, _, own_s, _, _) in table.items():
        for part, fraction in parts_of(function, frozenset()).items():
            seconds[part] = seconds.get(part, 0.0) + fraction * own_s
    total_s = sum(seconds.values())
    return sorted(
        (PartTime(part, s, s / total_s if total_s > 0 else 0.0) for part, s in seconds.items()),
        key=lambda p: -p.seconds,
    )


def top_functions(stats: pstats.Stats, count: int) -> list[tuple[str, int, float, str]]:
    """The ``count`` functions with the most exclusive time: (where, calls, seconds, part)."""
    table = stats.stats  # type: ignore[attr-defined]
    rows = []
    for (path, line, name), (_, calls, own_s, _, _) in table.items():
        where = name if path == "~" else f"{_short(path)}:{line}({name})"
        rows.append((where, calls, own_s, part_of_file(path) or "library"))
    return sorted(rows, key=lambda r: -r[2])[:count]


def _short(path: str) -> str:
    """A path from the package or library folder on (controller/..., cv2/..., ...)."""
    path = path.replace("\\", "/")
    for root in ("site-packages/", "controller/", "drivers/", "core/", "evaluation/"):
        if root in path:
            start = path.index(root)
            return path[start + (len(root) if root == "site-packages/" else 0) :]
    return path
