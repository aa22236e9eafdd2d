#!/usr/bin/env python3
"""Episode tools (summary, plot, reestimate, export to LeRobot, repair); see
controller/cli/replay.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("controller.cli.replay")
