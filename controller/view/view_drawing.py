"""Drawing the live view on a pygame ``Surface`` (no window needed: with
``SDL_VIDEODRIVER=dummy`` it draws the same pixels).

Layout (``SIZE`` = 1000 x 640 px)::

    +---------------- IMAGE ---------+----------- DIVERGENCE ------+-- BARS --+
    | tactile image, displacement    | div heat map (red +, blue -),| tau_x    |
    | arrows (ARROW colour)          | C+ and C- centroids, their   | tau_y    |
    |                                | midpoint, the dipole arrow p | tau_z    |
    +---------------------------------- PLOT ------------------------------------+
    | tau_x, tau_y, tau_z over the last 10 s (each scaled to its own range)     |
    +---------------------------------- STATUS ----------------------------------+
    | PHASE (its colour)   in control   pad / deadman / e-stop   the mapping    |

Each torque has its colour (``TAU_COLOURS``) in the bars and the plot; a bar's full scale
is the largest magnitude of that torque in the plot's window (at least ``FLOOR``), printed
beside it with the unit: N*mm when the estimate is calibrated, else the estimator's raw
units (mm for tau_x, tau_y; mm^2 for tau_z), labelled "raw".

The dipole arrow is the moment p the tilt torques come from (tau_x = c_x p_y,
tau_y = -c_y p_x: controller/tactile/dipole.py), drawn from the centroids' midpoint in the
image's axes (S's x right, y down), its length relative to the tilt bars' scale. It is the
estimator's p, taken about its own origin (the grasp's contact by default), so with
several regions of each sign it need not point from C- to C+.
"""

from __future__ import annotations

import math
import os
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")  # no banner on stdout at import

import pygame  # noqa: E402

if TYPE_CHECKING:
    from controller.view.snapshot import ViewSnapshot  # noqa: E402

SIZE = (1000, 640)
IMAGE = pygame.Rect(0, 0, 400, 300)
DIVERGENCE = pygame.Rect(410, 0, 400, 300)
BARS = pygame.Rect(820, 0, 180, 300)
PLOT = pygame.Rect(0, 310, 1000, 200)
STATUS = pygame.Rect(0, 520, 1000, 120)
PHASE_LABEL = pygame.Rect(10, 530, 300, 48)
HISTORY_S = 10.0
DIPOLE_PX = 120.0
"""The dipole arrow's length (px) at the tilt bars' full scale."""

BACKGROUND = (18, 18, 24)
ARROW = (0, 255, 255)
POSITIVE = (235, 60, 60)
NEGATIVE = (60, 110, 235)
MIDPOINT = (255, 255, 255)
DIPOLE = (255, 215, 0)
TEXT = (220, 220, 220)
TAU_COLOURS = ((255, 120, 40), (60, 220, 90), (190, 110, 255))
TAU_NAMES = ("tau_x", "tau_y", "tau_z")
FLOOR = (2e-4, 2e-4, 5e-3)
"""Least full scale of each bar and plot, raw units (the tilt noise floor's order)."""
PHASE_COLOURS = {"teleop": (255, 165, 0), "estop": (255, 40, 40), "failed": (255, 40, 40),
                 "done": (120, 200, 255)}  # fmt: skip
AUTONOMY_COLOUR = (120, 230, 120)


@dataclass
class ViewState:
    """What the view remembers between frames: the torque history (t, tau_x, tau_y,
    tau_z), the mapping's lines, and a status line (e.g. "paused")."""

    history: deque[tuple[float, float, float, float]]
    mapping: Sequence[str]
    note: str = ""
    fonts: dict[int, pygame.font.Font] = field(default_factory=dict)

    @classmethod
    def new(cls, mapping: Sequence[str]) -> ViewState:
        return cls(deque(), tuple(mapping))

    def font(self, size: int) -> pygame.font.Font:
        """pygame's default font at ``size`` px, loaded once per view."""
        if size not in self.fonts:
            self.fonts[size] = pygame.font.Font(None, size)
        return self.fonts[size]

    def add(self, snapshot: ViewSnapshot) -> None:
        """Append ``snapshot``'s torques and drop what is older than ``HISTORY_S``."""
        self.history.append((snapshot.t_s, *snapshot.tau))
        while self.history and self.history[0][0] < snapshot.t_s - HISTORY_S:
            self.history.popleft()


def draw(surface: pygame.Surface, snapshot: ViewSnapshot, state: ViewState) -> None:
    """Draw the whole view for ``snapshot`` on ``surface`` (at least ``SIZE``)."""
    surface.fill(BACKGROUND)
    font = state.font(22)
    _image_panel(surface, snapshot)
    scales = _scales(state)
    _divergence_panel(surface, snapshot, scales)
    _bars(surface, snapshot, scales, font, state.font(17))
    _plot(surface, state, scales, font)
    _status(surface, snapshot, state, font)


def _grid_to_px(snapshot: ViewSnapshot, rect: pygame.Rect) -> tuple[np.ndarray, np.ndarray]:
    """Pixel x (cols,) and y (rows,) in ``rect`` of the field's cell centres (the image
    scaled to the rect, S's origin at its centre)."""
    assert snapshot.x_mm is not None and snapshot.y_mm is not None
    height, width = snapshot.image.shape[:2] if snapshot.image is not None else (240, 320)
    scale = min(rect.width / width, rect.height / height)
    xs = rect.centerx + np.asarray(snapshot.x_mm) / snapshot.mm_per_px * scale
    ys = rect.centery + np.asarray(snapshot.y_mm) / snapshot.mm_per_px * scale
    return xs, ys


def _image_panel(surface: pygame.Surface, snapshot: ViewSnapshot) -> None:
    if snapshot.image is not None:
        rgb = np.ascontiguousarray(snapshot.image[:, :, 2::-1].swapaxes(0, 1))
        frame = pygame.transform.scale(pygame.surfarray.make_surface(rgb), IMAGE.size)
        surface.blit(frame, IMAGE.topleft)
    if snapshot.u_mm is None or snapshot.v_mm is None:
        return
    xs, ys = _grid_to_px(snapshot, IMAGE)
    u, v = np.asarray(snapshot.u_mm), np.asarray(snapshot.v_mm)
    cell_px = float(np.min(np.diff(xs))) if xs.size > 1 else 10.0
    largest = max(float(np.max(np.hypot(u, v))), 0.005)
    gain = 0.9 * cell_px / largest  # px per mm: the largest arrow spans most of a cell
    ends_x, ends_y = xs[None, :] + gain * u, ys[:, None] + gain * v
    for i, y in enumerate(ys.tolist()):
        for j, x in enumerate(xs.tolist()):
            end = (float(ends_x[i, j]), float(ends_y[i, j]))
            pygame.draw.line(surface, ARROW, (x, y), end, 2)
            pygame.draw.rect(surface, ARROW, (end[0] - 2, end[1] - 2, 4, 4))


def _divergence_panel(
    surface: pygame.Surface, snapshot: ViewSnapshot, scales: Sequence[float]
) -> None:
    pygame.draw.rect(surface, (40, 40, 48), DIVERGENCE)
    if snapshot.div is None:
        return
    div = np.asarray(snapshot.div)
    xs, ys = _grid_to_px(snapshot, DIVERGENCE)
    w = float(np.min(np.diff(xs))) if xs.size > 1 else 10.0
    h = float(np.min(np.diff(ys))) if ys.size > 1 else 10.0
    level = np.clip(np.abs(div) / max(float(np.max(np.abs(div))), 1e-6), 0.0, 1.0)
    base = np.where((div > 0)[..., None], POSITIVE, NEGATIVE)
    cells = (40 + (base - 40) * level[..., None]).astype(np.uint8)  # (rows, cols, 3)
    heat = pygame.transform.scale(
        pygame.surfarray.make_surface(cells.swapaxes(0, 1)),
        (round(w * xs.size), round(h * ys.size)),
    )
    surface.blit(heat, (xs[0] - w / 2, ys[0] - h / 2))
    centroids: list[tuple[float, float] | None] = []
    for sign, colour in ((1.0, POSITIVE), (-1.0, NEGATIVE)):
        mass = np.maximum(sign * div, 0.0)
        total = float(mass.sum())
        if total <= 0.0:
            centroids.append(None)
            continue
        cx = float((mass.sum(axis=0) * xs).sum() / total)
        cy = float((mass.sum(axis=1) * ys).sum() / total)
        centroids.append((cx, cy))
        pygame.draw.circle(surface, (255, 255, 255), (cx, cy), 9)
        pygame.draw.circle(surface, colour, (cx, cy), 7)
    plus, minus = centroids
    mid = None
    if plus is not None and minus is not None:
        mid = ((plus[0] + minus[0]) / 2, (plus[1] + minus[1]) / 2)
        pygame.draw.circle(surface, MIDPOINT, mid, 5)
    # the dipole moment the torques come from: tau_x = c_x p_y, tau_y = -c_y p_x (dipole.py)
    tau_x, tau_y = snapshot.tau[0], snapshot.tau[1]
    if math.isfinite(tau_x) and math.isfinite(tau_y) and (tau_x or tau_y):
        start = mid if mid is not None else DIVERGENCE.center
        p_x, p_y = -tau_y, tau_x
        length = DIPOLE_PX * min(1.0, math.hypot(p_x, p_y) / max(scales[0], scales[1]))
        norm = math.hypot(p_x, p_y)
        end = (start[0] + length * p_x / norm, start[1] + length * p_y / norm)
        _arrow(surface, DIPOLE, start, end)


def _arrow(surface: pygame.Surface, colour: tuple[int, int, int], start: tuple[float, float],
           end: tuple[float, float]) -> None:  # fmt: skip
    pygame.draw.line(surface, colour, start, end, 4)
    angle = math.atan2(end[1] - start[1], end[0] - start[0])
    for turn in (2.6, -2.6):
        tip = (end[0] + 12 * math.cos(angle + turn), end[1] + 12 * math.sin(angle + turn))
        pygame.draw.line(surface, colour, end, tip, 4)


def _scales(state: ViewState) -> tuple[float, float, float]:
    """Each torque's full scale: its largest magnitude in the history, at least FLOOR."""
    if not state.history:
        return FLOOR
    values = np.abs(np.array(state.history)[:, 1:])
    peaks = np.nanmax(np.where(np.isfinite(values), values, 0.0), axis=0)
    return tuple(max(float(p), f) for p, f in zip(peaks, FLOOR, strict=True))  # type: ignore[return-value]


def unit_label(index: int, calibrated: bool) -> str:
    """The unit a torque is shown in: N*mm calibrated, else the raw unit."""
    if calibrated:
        return "N*mm"
    return "raw mm^2" if index == 2 else "raw mm"


def _bars(surface: pygame.Surface, snapshot: ViewSnapshot, scales: Sequence[float],
          font: pygame.font.Font, small: pygame.font.Font) -> None:  # fmt: skip
    width = BARS.width // 3
    half = (BARS.height - 70) / 2
    zero_y = BARS.y + 30 + half
    factor = 1000.0 if snapshot.calibrated else 1.0
    for k, (value, scale) in enumerate(zip(snapshot.tau, scales, strict=True)):
        x = BARS.x + k * width + 8
        pygame.draw.line(surface, TEXT, (x - 4, zero_y), (x + width - 12, zero_y), 1)
        if math.isfinite(value):
            length = max(-1.0, min(1.0, value / scale)) * half
            top = zero_y - max(length, 0.0)
            pygame.draw.rect(surface, TAU_COLOURS[k],
                             pygame.Rect(x, top, width - 16, max(abs(length), 2.0)))  # fmt: skip
        surface.blit(font.render(TAU_NAMES[k], True, TAU_COLOURS[k]), (x - 4, BARS.y + 4))
        shown = f"{value * factor:+.1e}" if math.isfinite(value) else "n/a"
        surface.blit(small.render(shown, True, TEXT), (x - 6, BARS.bottom - 38))
    units = f"{unit_label(0, snapshot.calibrated)} / {unit_label(2, snapshot.calibrated)}"
    surface.blit(font.render(units, True, TEXT), (BARS.x, BARS.bottom - 18))


def _plot(surface: pygame.Surface, state: ViewState, scales: Sequence[float],
          font: pygame.font.Font) -> None:  # fmt: skip
    pygame.draw.rect(surface, (30, 30, 38), PLOT)
    mid = PLOT.centery
    pygame.draw.line(surface, (90, 90, 90), (PLOT.x, mid), (PLOT.right, mid), 1)
    surface.blit(font.render(f"last {HISTORY_S:g} s", True, TEXT), (PLOT.x + 6, PLOT.y + 4))
    if len(state.history) < 2:
        return
    rows = np.array(state.history)
    t_end = rows[-1, 0]
    xs = PLOT.right - (t_end - rows[:, 0]) / HISTORY_S * PLOT.width
    for k in range(3):
        ys = mid - np.clip(rows[:, k + 1] / scales[k], -1.0, 1.0) * (PLOT.height / 2 - 8)
        finite = np.isfinite(ys)
        points = list(zip(xs[finite].tolist(), ys[finite].tolist(), strict=True))
        if len(points) >= 2:
            pygame.draw.lines(surface, TAU_COLOURS[k], False, points, 2)


def _status(surface: pygame.Surface, snapshot: ViewSnapshot, state: ViewState,
            font: pygame.font.Font) -> None:  # fmt: skip
    phase_colour = PHASE_COLOURS.get(snapshot.phase, AUTONOMY_COLOUR)
    pygame.draw.rect(surface, phase_colour, PHASE_LABEL, border_radius=6)
    surface.blit(state.font(40).render(snapshot.phase.upper(), True, BACKGROUND),
                 (PHASE_LABEL.x + 10, PHASE_LABEL.y + 10))  # fmt: skip
    who = "operator" if snapshot.operator else "autonomy"
    lines = [
        f"in control: {who}",
        f"pad: {'connected' if snapshot.connected else 'UNPLUGGED'}   "
        f"deadman: {'held' if snapshot.deadman else 'released'}   "
        f"e-stop: {'ACTIVE' if snapshot.estop else 'clear'}",
        f"t = {snapshot.t_s:7.2f} s   {state.note}",
    ]
    for i, line in enumerate(lines):
        colour = (255, 80, 80) if ("UNPLUGGED" in line or "ACTIVE" in line) else TEXT
        surface.blit(font.render(line, True, colour), (10, PHASE_LABEL.bottom + 4 + 18 * i))
    for i, line in enumerate(state.mapping[:6]):
        surface.blit(font.render(line, True, TEXT), (340, STATUS.y + 8 + 18 * i))
