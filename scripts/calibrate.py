#!/usr/bin/env python3
"""Fit c_x, c_y (and c_z) on a calibration dataset; see controller/cli/calibrate.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("controller.cli.calibrate")
