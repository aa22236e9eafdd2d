"""The live view's window, in its own process: ``LiveView`` (the run's side) and
``run_window`` (the view process).

Why a process: the view never slows the control loop (its drawing and SDL's event pump run
on another interpreter and core), and its SDL instance is its own, so a real gamepad read
through pygame in the run's process (which owns that process's SDL event queue) does not
eat the view's key presses.

Frames: ``LiveView.offer`` puts a snapshot on a queue of ``QUEUE_FRAMES`` without waiting;
when the view has not taken the previous ones the snapshot is dropped and counted
(``dropped``), so the view shows the newest frames it can draw, never a backlog.

Without a display the view says so once ('error ...' to the run's side, which prints one
line and goes on without it): when the window cannot open, and when SDL silently falls back
to a driver that draws to no window (its 'offscreen' driver, ``WINDOWLESS_DRIVERS``).

Keys (``KEYS``): ``z`` re-zero the tactile reference, ``p`` or space pause the picture
(the run goes on), ``s`` save a screenshot (``screenshot-NNN.png`` in the output folder,
written atomically), ``q`` or Esc quit. Quitting, or closing the window, sends ``quit``:
the run's side ends the run safely (``LiveView.watch``'s callback).
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import queue
import threading
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from controller.view.snapshot import ViewSnapshot

WINDOWLESS_DRIVERS = ("offscreen", "dummy")
"""SDL video drivers that draw to no window; SDL falls back to 'offscreen' without a
display, which the view reports as it does a failed open (unless asked for by name)."""
QUEUE_FRAMES = 2
KEYS = ("z: re-zero", "p / space: pause", "s: screenshot", "q / Esc: quit")
JOIN_S = 3.0


class LiveView:
    """The run's handle on the view process (see the module doc). ``mapping``: lines
    describing the gamepad mapping; ``out_dir``: where screenshots go."""

    def __init__(self, mapping: Sequence[str], out_dir: Path) -> None:
        context = multiprocessing.get_context("spawn")
        self._snapshots: Any = context.Queue(maxsize=QUEUE_FRAMES)
        self._commands: Any = context.Queue()
        self._process = context.Process(
            target=run_window,
            args=(self._snapshots, self._commands, tuple(mapping), str(out_dir)),
            name="live-view",
            daemon=True,
        )
        self.dropped = 0
        self.offered = 0
        self._closing = False
        self._watcher: threading.Thread | None = None

    def start(self) -> None:
        self._process.start()

    def offer(self, snapshot: ViewSnapshot) -> None:
        """Hand ``snapshot`` to the view, or drop it if the view is behind (never waits)."""
        self.offered += 1
        try:
            self._snapshots.put_nowait(snapshot)
        except queue.Full:
            self.dropped += 1

    def watch(self, on_command: Callable[[str], None]) -> None:
        """Call ``on_command`` with each key command the view sends ('rezero', 'quit',
        'screenshot PATH', or 'error MESSAGE' if it could not open its window), on a thread
        of its own, until the view ends."""

        def read() -> None:
            while True:
                try:
                    command = self._commands.get(timeout=0.2)
                except queue.Empty:
                    if not self._process.is_alive():
                        return
                    continue
                if self._closing:  # a terminated view reports SDL's quit: not the user's
                    return
                on_command(command)
                if command == "quit":
                    return

        self._watcher = threading.Thread(target=read, name="live-view-keys", daemon=True)
        self._watcher.start()

    @property
    def alive(self) -> bool:
        return self._process.is_alive()

    def close(self) -> None:
        """Ask the view to end and wait for it (terminated after ``JOIN_S``)."""
        self._closing = True
        if self._process.is_alive():
            try:
                self._snapshots.put(None, timeout=1.0)
            except queue.Full:
                pass
        self._process.join(JOIN_S)
        if self._process.is_alive():
            self._process.terminate()
            self._process.join(JOIN_S)
        self._snapshots.cancel_join_thread()


def run_window(snapshots: Any, commands: Any, mapping: Sequence[str], out_dir: str) -> None:
    """The view process: open the window, draw each snapshot, send key commands."""
    os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
    import pygame

    from controller.view.view_drawing import SIZE, ViewState, draw

    try:
        with _stderr_quiet():  # SDL's own lines (XDG_RUNTIME_DIR ...): the tool says it once
            pygame.display.init()
            pygame.font.init()
            screen = pygame.display.set_mode(SIZE)
    except pygame.error as error:  # no display: say so once, the run goes on without a view
        commands.put(f"error {error}")
        return
    driver = pygame.display.get_driver()
    if driver in WINDOWLESS_DRIVERS and os.environ.get("SDL_VIDEODRIVER") != driver:
        pygame.quit()  # SDL fell back to drawing nowhere: no window appeared
        commands.put(f"error no display: SDL fell back to its '{driver}' video driver")
        return
    pygame.display.set_caption("tactile-insertion: teleop live view")
    state = ViewState.new([*mapping, "keys: " + ", ".join(KEYS)])
    paused = False
    shots = 0
    parent = multiprocessing.parent_process()
    try:
        while True:
            for event in pygame.event.get():
                if event.type == pygame.QUIT or (
                    event.type == pygame.KEYDOWN and event.key in (pygame.K_q, pygame.K_ESCAPE)
                ):
                    commands.put("quit")
                    return
                if event.type != pygame.KEYDOWN:
                    continue
                if event.key == pygame.K_z:
                    commands.put("rezero")
                elif event.key in (pygame.K_p, pygame.K_SPACE):
                    paused = not paused
                    state.note = "PAUSED (p: resume)" if paused else ""
                elif event.key == pygame.K_s:
                    shots += 1
                    path = save_screenshot(screen, Path(out_dir), shots)
                    commands.put(f"screenshot {path}")
            try:
                snapshot = snapshots.get(timeout=0.05)
            except queue.Empty:
                if parent is not None and not parent.is_alive():
                    return
                continue
            if snapshot is None:
                return
            state.add(snapshot)
            if not paused:
                draw(screen, snapshot, state)
                pygame.display.flip()
    finally:
        pygame.quit()


@contextlib.contextmanager
def _stderr_quiet() -> Iterator[None]:
    """File descriptor 2 pointed at /dev/null for the block (SDL writes there itself)."""
    saved = os.dup(2)
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(devnull, 2)
        yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)
        os.close(devnull)


def save_screenshot(surface: Any, out_dir: Path, number: int) -> Path:
    """``surface`` as ``out_dir/screenshot-NNN.png``, written atomically."""
    import pygame

    from core.atomic_files import atomic_file

    path = out_dir / f"screenshot-{number:03d}.png"
    with atomic_file(path) as partial:  # the same .png suffix: pygame picks PNG from it
        pygame.image.save(surface, str(partial))
    return path
