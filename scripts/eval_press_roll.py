#!/usr/bin/env python3
"""Tilt estimates on a simulated ball pressed and rolled; see
evaluation/experiments/press_roll_eval.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("evaluation.experiments.press_roll_eval")
