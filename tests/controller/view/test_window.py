"""The view's process: it starts, takes frames without making the caller wait (dropping
what it cannot take), ends when asked; screenshots are written whole."""

import os

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")

import time  # noqa: E402

import pygame  # noqa: E402

from controller.view import window  # noqa: E402
from tests.controller.view.test_view_drawing import snapshot  # noqa: E402


def test_offers_never_wait_and_the_view_process_ends_when_closed(tmp_path):
    view = window.LiveView(["vx: lefty"], tmp_path)
    view.start()
    began = time.perf_counter()
    for k in range(50):  # faster than the process (still starting) takes them
        view.offer(snapshot(t_s=0.04 * k))
    offered_s = time.perf_counter() - began
    assert view.offered == 50 and view.dropped >= 50 - window.QUEUE_FRAMES
    assert offered_s < 1.0  # (not a speed test: a generous bound that a blocking put would miss)
    commands = []
    view.watch(commands.append)
    view.close()
    assert not view.alive
    assert commands == []


def test_a_screenshot_is_a_whole_png_named_in_order(tmp_path):
    pygame.display.init()
    try:
        surface = pygame.Surface((40, 30))
        surface.fill((200, 10, 10))
        path = window.save_screenshot(surface, tmp_path, 3)
        assert path == tmp_path / "screenshot-003.png"
        assert pygame.image.load(str(path)).get_at((5, 5))[:3] == (200, 10, 10)
        assert [p.name for p in tmp_path.iterdir()] == ["screenshot-003.png"]
    finally:
        pygame.quit()


def test_a_view_without_a_display_says_so_once_and_ends(tmp_path, monkeypatch):
    monkeypatch.setenv("SDL_VIDEODRIVER", "no_such_driver")  # the view's process inherits it
    view = window.LiveView([], tmp_path)
    view.start()
    commands = []
    view.watch(commands.append)
    deadline = time.monotonic() + 60.0
    while view.alive and time.monotonic() < deadline:
        time.sleep(0.05)
    time.sleep(0.5)  # the watcher's last read
    view.close()
    assert len(commands) == 1 and commands[0].startswith("error ")
    assert "no_such_driver" in commands[0]


def test_a_view_that_sdl_puts_offscreen_says_no_window_appeared(tmp_path, monkeypatch):
    for name in ("SDL_VIDEODRIVER", "DISPLAY", "WAYLAND_DISPLAY"):  # no display at all
        monkeypatch.delenv(name, raising=False)
    view = window.LiveView([], tmp_path)
    view.start()
    commands = []
    view.watch(commands.append)
    deadline = time.monotonic() + 60.0
    while view.alive and time.monotonic() < deadline:
        time.sleep(0.05)
    time.sleep(0.5)  # the watcher's last read
    view.close()
    assert commands == ["error no display: SDL fell back to its 'offscreen' video driver"]
