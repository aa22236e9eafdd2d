#!/usr/bin/env python3
"""One insertion trial, simulated or on the robot; see controller/cli/trial_cli.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("controller.cli.trial_cli")
