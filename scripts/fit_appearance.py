#!/usr/bin/env python3
"""Fit the renderer's realistic looks to the shipped real captures; see
evaluation/appearance/fit.py. ``python scripts/fit_appearance.py [realistic|realistic_digit]``."""

import sys

from evaluation.appearance.fit import main

if __name__ == "__main__":
    sys.exit(main())
