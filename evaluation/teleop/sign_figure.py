"""``python -m evaluation teleop_sign_figure``: the drawing of the alignment demo's two
manoeuvres and the signs of the tilt torques they give (docs/figures/teleop_signs.png,
docs/USER_GUIDE.md).

    teleop_sign_figure.py --out docs/figures/teleop_signs.png
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

from core.subcommands import job_prog

matplotlib.use("Agg")
import matplotlib.patches as patches  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.axes import Axes  # noqa: E402

from controller.cli.support import ToolError, run_tool  # noqa: E402
from core.atomic_files import atomic_file  # noqa: E402

BOARD = "#b0a58f"
PLUG = "#6a7fa8"
GEL = "#e07a5f"
MOVE = "#1d7a3a"
FORCE = "#c0392b"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog=job_prog("teleop_sign_figure"), description=__doc__.splitlines()[0]
    )
    parser.add_argument("--out", type=Path, required=True, help="the PNG to write")
    args = parser.parse_args(argv)
    return run_tool("teleop_sign_figure", lambda: _run(args.out))


def _run(out: Path) -> int:
    if out.suffix.lower() != ".png":
        raise ToolError(f"--out '{out}': expected a .png file")
    figure, (side, top) = plt.subplots(1, 2, figsize=(11, 5.2))
    _translation(side)
    _rotation(top)
    figure.tight_layout()
    with atomic_file(out) as partial:
        figure.savefig(partial, dpi=110)
    plt.close(figure)
    print(f"teleop_sign_figure: wrote {out}")
    return 0


def _axes_key(ax: Axes, origin: tuple[float, float], right: str, up: str, out: str) -> None:
    x, y = origin
    ax.annotate("", (x + 1.2, y), (x, y), arrowprops={"arrowstyle": "->", "lw": 1.5})
    ax.annotate("", (x, y + 1.2), (x, y), arrowprops={"arrowstyle": "->", "lw": 1.5})
    ax.text(x + 1.3, y - 0.1, right, fontsize=10)
    ax.text(x - 0.2, y + 1.35, up, fontsize=10)
    ax.text(x - 0.6, y - 0.5, out, fontsize=9)


def _translation(ax: Axes) -> None:
    """Side view (S x out of the page): the plug partly in the opening, the TCP moved along
    +S z, the opening's wall holding the tip back, the gel's torque tau_x > 0."""
    ax.set_title("translate along +S z (pad vy > 0): tau_x > 0", fontsize=12)
    ax.add_patch(patches.Rectangle((-6, -3), 4.7, 3, color=BOARD))
    ax.add_patch(patches.Rectangle((1.3, -3), 4.7, 3, color=BOARD))
    ax.text(-5.8, -2.5, "board", fontsize=9)
    ax.add_patch(patches.Rectangle((-1.2, -1.5), 2.4, 9.5, color=PLUG, alpha=0.9))
    ax.text(-1.0, 6.8, "plug", color="white", fontsize=9)
    ax.add_patch(patches.Rectangle((-2.0, 4.0), 0.8, 3.0, color=GEL))
    ax.text(-4.4, 5.6, "gel\n(camera\nbehind)", fontsize=8)
    ax.plot([-1.6], [5.5], "ko")
    ax.text(-4.6, 3.3, "S origin: gel centre", fontsize=8)
    ax.annotate("", (3.5, 8.6), (0.2, 8.6), arrowprops={"arrowstyle": "->", "lw": 3, "color": MOVE})
    ax.text(0.3, 9.0, "TCP moves +S z", color=MOVE, fontsize=10)
    ax.annotate("", (0.0, -0.9), (2.6, -0.9), arrowprops={"arrowstyle": "->", "lw": 3,
                                                            "color": FORCE})  # fmt: skip
    ax.text(2.0, -2.2, "wall holds the tip: force -S z", color=FORCE, fontsize=9)
    ax.add_patch(patches.Arc((-1.6, 5.5), 5.0, 5.0, theta1=200, theta2=330, lw=2.5, color=GEL))
    ax.annotate("", (0.5, 4.2), (0.3, 3.9), arrowprops={"arrowstyle": "->", "lw": 2.5,
                                                          "color": GEL})  # fmt: skip
    ax.text(2.6, 3.2, "gel's torque on the plug:\ntau_x > 0 (about +S x, out of page)",
            color=GEL, fontsize=9)  # fmt: skip
    _axes_key(ax, (-5.5, 7.5), "S z", "-S y (up)", "S x: out of page")
    _frame(ax, (-6.5, 7.5), (-3.5, 10.0))


def _rotation(ax: Axes) -> None:
    """Top view (looking down the plug, S y into the page): the plug's cross-section turned
    about +S y (clockwise as drawn) in the opening, the walls stopping it, tau_y > 0."""
    ax.set_title("rotate about +S y (pad wz < 0): tau_y > 0", fontsize=12)
    ax.add_patch(patches.Rectangle((-6, -3), 12, 6, color=BOARD))
    ax.add_patch(patches.Rectangle((-4.17, -1.28), 8.34, 2.56, color="white"))
    ax.text(-5.8, 2.4, "board, opening (8.34 x 2.56 mm)", fontsize=9)
    plug = patches.Rectangle((-4.12, -1.2), 8.25, 2.4, color=PLUG, alpha=0.85)
    turn = matplotlib.transforms.Affine2D().rotate_deg(-1.2) + ax.transData
    plug.set_transform(turn)
    ax.add_patch(plug)
    ax.add_patch(patches.Arc((0, 0), 6.0, 6.0, theta1=100, theta2=170, lw=3, color=MOVE))
    ax.annotate("", (-0.6, 2.95), (-1.0, 2.85), arrowprops={"arrowstyle": "<-", "lw": 3,
                                                              "color": MOVE})  # fmt: skip
    ax.text(-3.5, 3.4, "TCP turns about +S y (clockwise here)", color=MOVE, fontsize=10)
    for head, tail in (((3.9, -1.3), (3.9, -2.4)), ((-3.9, 1.3), (-3.9, 2.4))):
        ax.annotate("", head, tail, arrowprops={"arrowstyle": "->", "lw": 2.5, "color": FORCE})
    ax.text(0.0, -2.7, "walls stop the twist", color=FORCE, fontsize=9)
    ax.text(-5.8, -4.3, "the gel turns the plug on: tau_y > 0 (about +S y, into the page)",
            color=GEL, fontsize=9)  # fmt: skip
    _axes_key(ax, (-5.5, 4.2), "S x", "S z", "S y: into page")
    _frame(ax, (-6.5, 6.5), (-4.8, 6.2))


def _frame(ax: Axes, xlim: tuple[float, float], ylim: tuple[float, float]) -> None:
    """A drawing's extent (mm), equal scales, no axes."""
    ax.set_xlim(*xlim)
    ax.set_ylim(*ylim)
    ax.set_aspect("equal")
    ax.axis("off")
