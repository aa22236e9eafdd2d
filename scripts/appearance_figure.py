#!/usr/bin/env python3
"""Real gel captures beside rendered frames (docs/figures/appearance.png) and the appearance
statistics table; see evaluation/appearance/figure.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("evaluation.appearance.figure")
