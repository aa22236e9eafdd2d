#!/usr/bin/env python3
"""The ``tactile`` command (every job: ``tactile.py --help``); see controller/cli/command.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("controller.cli.command")
