#!/usr/bin/env python3
"""Fit the renderer's realistic looks to the shipped real captures; see
evaluation/appearance/fit.py. ``python scripts/fit_appearance.py [realistic|realistic_digit]``."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("evaluation.appearance.fit")
