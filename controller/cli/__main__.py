"""``python -m controller.cli``: the ``tactile`` command."""

from controller.cli.tactile import run

run()
