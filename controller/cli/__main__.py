"""``python -m controller.cli``: the ``tactile`` command."""

from controller.cli.tactile import run

if __name__ == "__main__":
    run()
