#!/usr/bin/env python3
"""Fit c_x, c_y (and c_z) on a calibration dataset; see evaluation/offline/calibrate_cli.py."""

import sys

from evaluation.offline.calibrate_cli import main

if __name__ == "__main__":
    sys.exit(main())
