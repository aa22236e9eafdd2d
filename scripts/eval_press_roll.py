#!/usr/bin/env python3
"""Tilt estimates on a simulated ball pressed and rolled; see
evaluation/experiments/press_roll_eval.py."""

import sys

from evaluation.experiments.press_roll_eval import main

if __name__ == "__main__":
    sys.exit(main())
