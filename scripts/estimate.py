#!/usr/bin/env python3
"""Offline torque estimation on recorded tactile frames; see controller/cli/estimate.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("controller.cli.estimate")
