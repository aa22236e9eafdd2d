"""The live view's drawing, headless (SDL_VIDEODRIVER=dummy): the picture's content."""

import os

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")

import numpy as np  # noqa: E402
import pygame  # noqa: E402
import pytest  # noqa: E402

from controller.view import view_drawing as render  # noqa: E402
from controller.view.snapshot import ViewSnapshot  # noqa: E402


@pytest.fixture(scope="module")
def surface():
    pygame.display.init()
    pygame.font.init()
    yield pygame.Surface(render.SIZE)
    pygame.quit()


def snapshot(t_s=1.0, tau=(0.001, -0.0005, 0.004), phase="teleop", **kw):
    x = np.linspace(-6.0, 6.0, 8)
    y = np.linspace(-4.5, 4.5, 6)
    xx, yy = np.meshgrid(x, y)
    u, v = 0.02 * xx / 6.0, 0.02 * yy / 4.5  # spreading toward +x, +y: a dipole along the diagonal
    div = np.where(xx + yy > 0, 1.0, -0.5) * 1e-3
    values = dict(t_s=t_s, image=np.full((240, 320, 3), 90, np.uint8), x_mm=x, y_mm=y, u_mm=u,
                  v_mm=v, div=div, tau=tau, calibrated=False, phase=phase, operator=True,
                  connected=True, deadman=True, estop=False, mm_per_px=0.0634)  # fmt: skip
    values.update(kw)
    return ViewSnapshot(**values)


def count(surface, rect, colour, tolerance=8):
    pixels = pygame.surfarray.pixels3d(surface)[rect.left : rect.right, rect.top : rect.bottom]
    return int(np.sum(np.all(np.abs(pixels.astype(int) - colour) <= tolerance, axis=-1)))


def test_the_view_draws_arrows_centroids_bars_plot_and_phase_where_expected(surface):
    state = render.ViewState.new(["vx: lefty"])
    for k in range(30):
        snap = snapshot(t_s=0.04 * k, tau=(0.001 * np.sin(k / 5), -0.0005, 0.004))
        state.add(snap)
    render.draw(surface, snap, state)
    assert count(surface, render.IMAGE, render.ARROW) > 100  # the displacement arrows
    assert count(surface, render.DIVERGENCE, render.DIPOLE) > 50  # the dipole arrow
    assert count(surface, render.DIVERGENCE, render.MIDPOINT) > 20
    for colour in render.TAU_COLOURS:  # each torque's bar and its plot line
        assert count(surface, render.BARS, colour) > 50
        assert count(surface, render.PLOT, colour) > 30
    label = render.PHASE_COLOURS["teleop"]
    assert count(surface, render.PHASE_LABEL, label) > 0.5 * render.PHASE_LABEL.width * 48
    assert count(surface, render.IMAGE, render.ARROW) < render.IMAGE.width * render.IMAGE.height / 2


def test_a_bar_grows_up_for_a_positive_torque_and_down_for_a_negative_one(surface):
    state = render.ViewState.new([])
    snap = snapshot(tau=(0.002, -0.002, 0.0))
    state.add(snap)
    render.draw(surface, snap, state)
    half = render.BARS.height // 2
    upper = pygame.Rect(render.BARS.x, render.BARS.y, render.BARS.width, half)
    lower = pygame.Rect(render.BARS.x, render.BARS.y + half, render.BARS.width, half)
    assert count(surface, upper, render.TAU_COLOURS[0]) > 500  # tau_x > 0: up
    assert count(surface, lower, render.TAU_COLOURS[0]) < 50
    assert count(surface, lower, render.TAU_COLOURS[1]) > 500  # tau_y < 0: down


def test_estop_shows_the_red_phase_label_and_units_say_raw(surface):
    state = render.ViewState.new([])
    snap = snapshot(phase="estop", estop=True)
    state.add(snap)
    render.draw(surface, snap, state)
    assert count(surface, render.PHASE_LABEL, render.PHASE_COLOURS["estop"]) > 5000
    assert render.unit_label(0, False) == "raw mm" and render.unit_label(2, False) == "raw mm^2"
    assert render.unit_label(1, True) == "N*mm"


def test_a_snapshot_without_a_field_draws_the_image_only(surface):
    state = render.ViewState.new([])
    snap = snapshot(x_mm=None, y_mm=None, u_mm=None, v_mm=None, div=None)
    state.add(snap)
    render.draw(surface, snap, state)
    assert count(surface, render.IMAGE, render.ARROW) == 0
    assert count(surface, render.IMAGE, (90, 90, 90), tolerance=0) > 10000  # the grey frame
