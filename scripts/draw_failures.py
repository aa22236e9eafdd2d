#!/usr/bin/env python3
"""Which per-seed scene draws a batch's failures share; see evaluation/trials/draw_failures.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("evaluation.trials.draw_failures")
