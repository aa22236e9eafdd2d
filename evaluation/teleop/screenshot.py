"""``python -m evaluation teleop_screenshot``: the live view's picture at a moment of a recorded
episode, drawn by the view's own code from the episode's streams.

    teleop_screenshot.py EPISODE --at T --out PICTURE.png

The view's snapshots are rebuilt from the episode in the loop's order (each
``/tactile/wrench`` message with the newest ``/tactile/image``, ``/tactile/field``,
``/loop/tick`` and ``/teleop/input`` before it), the torque history of the 10 s up to the
frame at ``T`` (s on the episode's clock; a time past its end is refused) is replayed,
and that frame is drawn
(``controller.view.view_drawing.draw``) off screen and written atomically. The README's
picture of the sim demo is made this way (docs/USER_GUIDE.md has the command).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from controller.cli.outputs import check_output_file
from controller.cli.support import ToolError, number, run_tool
from controller.episode import EpisodeError, decode_image, grid_arrays, read_episode
from controller.view.snapshot import ViewSnapshot
from core.atomic_files import atomic_file
from core.config import CONFIG_ROOT, resolve_config_path
from core.sensor_profile import sensor_profile
from core.subcommands import job_prog
from drivers import registry


def _warn(message: str) -> None:
    print(f"teleop_screenshot: warning: {message}", file=sys.stderr)


STREAMS = ("/tactile/image", "/tactile/field", "/tactile/wrench", "/loop/tick", "/teleop/input")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog=job_prog("teleop_screenshot"), description=__doc__.splitlines()[0]
    )
    parser.add_argument("episode", type=Path)
    parser.add_argument("--at", type=number(0.0, 1e6, "s"), required=True)
    parser.add_argument("--out", type=Path, required=True, help="the PNG to write")
    args = parser.parse_args(argv)
    return run_tool("teleop_screenshot", lambda: _run(args.episode, args.at, args.out))


def _run(path: Path, at_s: float, out: Path) -> int:
    if out.suffix.lower() != ".png":
        raise ToolError(f"--out '{out}': expected a .png file")
    check_output_file(out, [path], option="--out")  # beside the episode is fine
    try:
        episode = read_episode(path)
    except EpisodeError as error:
        raise ToolError(str(error)) from None
    if episode.damaged:
        _warn(f"episode '{path}' is damaged: {episode.lost_bytes} bytes could not be read "
              f"({episode.lost_text()}); drawing from the rest")  # fmt: skip
    start_s, end_s = episode.time_range_s()
    if not math.isfinite(end_s):
        raise ToolError(f"episode '{path}': no messages (the run ended before its first tick)")
    if at_s > end_s:
        raise ToolError(
            f"--at {at_s:g}: past the episode's end; expected a time in [0, {end_s:.2f}] s "
            f"(its messages run from {start_s:.2f} to {end_s:.2f} s)"
        )
    try:
        mm_per_px = sensor_profile(_task_sensor(episode)).mm_per_px
    except (KeyError, TypeError, yaml.YAMLError) as error:
        raise ToolError(
            f"episode '{path}': its task.yaml attachment names no tactile sensor ({error})"
        ) from None
    try:
        snapshots = [s for s in snapshots_of(episode, mm_per_px) if s.t_s <= at_s]
    except EpisodeError as error:
        raise ToolError(str(error)) from None
    except (KeyError, TypeError, ValueError) as error:  # a hand-made file's messages
        raise ToolError(
            f"episode '{path}': a message lacks what this package's writer writes "
            f"({type(error).__name__}: {error})"
        ) from None
    if not snapshots:
        raise ToolError(f"--at {at_s}: the episode has no tactile estimate by then")
    os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
    os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
    import pygame

    from controller.view.view_drawing import SIZE, ViewState, draw

    pygame.display.init()
    pygame.font.init()
    try:
        state = ViewState.new([f"episode {path.name}, t = {snapshots[-1].t_s:.2f} s"])
        for snapshot in snapshots:
            state.add(snapshot)
        surface = pygame.Surface(SIZE)
        draw(surface, snapshots[-1], state)
        with atomic_file(out) as partial:
            pygame.image.save(surface, str(partial))
    finally:
        pygame.quit()
    print(f"teleop_screenshot: wrote {out} (frame at {snapshots[-1].t_s:.2f} s)")
    return 0


def _task_sensor(episode: Any) -> str:
    """The tactile sensor's model (its profile) from the episode's resolved task."""
    raw = yaml.safe_load(episode.attachments["task.yaml"])
    tactile = resolve_config_path(raw["devices"]["tactile"], "sensors")
    if not tactile.is_absolute():
        tactile = CONFIG_ROOT / tactile
    return str(registry.load_device_config(tactile, "real", "tactile").config.model)


def snapshots_of(episode: Any, mm_per_px: float) -> list[ViewSnapshot]:
    """The view's snapshot of every tactile estimate of ``episode``, in order."""
    image = grid = tick = teleop = None
    out = []
    for message in episode.messages(*STREAMS):
        value = message.value
        if message.topic == "/tactile/image":
            image, grid = decode_image(value), None
        elif message.topic == "/tactile/field":
            grid = value
        elif message.topic == "/loop/tick":
            tick = value
        elif message.topic == "/teleop/input":
            teleop = value
        else:
            out.append(_snapshot(value, image, grid, tick, teleop, mm_per_px))
    return out


def _torques(wrench: Any) -> tuple[float, float, float]:
    """(tau_x, tau_y, tau_z) of a ``/tactile/wrench`` message, NaN for null."""
    x, y, z = (
        math.nan if wrench[k] is None else float(wrench[k]) for k in ("tau_x", "tau_y", "tau_z")
    )
    return x, y, z


def _snapshot(wrench: Any, image: Any, grid: Any, tick: Any, teleop: Any,
              mm_per_px: float) -> ViewSnapshot:  # fmt: skip
    fields = x_mm = y_mm = None
    if grid is not None:
        fields = grid_arrays(grid)
        rows, cols = fields["u_mm"].shape
        x_mm = (grid.pose.position.x + (np.arange(cols) + 0.5) * grid.cell_size.x) * 1e3
        y_mm = (grid.pose.position.y + (np.arange(rows) + 0.5) * grid.cell_size.y) * 1e3
    teleop = teleop or {}
    phase = tick["phase"] if tick is not None else "starting"
    return ViewSnapshot(
        t_s=wrench["t_s"], image=image, x_mm=x_mm, y_mm=y_mm,
        u_mm=None if fields is None else fields["u_mm"],
        v_mm=None if fields is None else fields["v_mm"],
        div=None if fields is None else fields["div"],
        tau=_torques(wrench),
        calibrated=wrench.get("calibrated", False), phase=phase,
        operator=teleop.get("in_control", False), connected=teleop.get("connected", False),
        deadman=teleop.get("deadman", False),
        estop=teleop.get("estop", False) or phase == "estop", mm_per_px=mm_per_px,
    )  # fmt: skip
