#!/usr/bin/env python3
"""Real gel captures beside rendered frames (docs/figures/appearance.png) and the appearance
statistics table; see evaluation/appearance/figure.py."""

import sys

from evaluation.appearance.figure import main

if __name__ == "__main__":
    sys.exit(main())
