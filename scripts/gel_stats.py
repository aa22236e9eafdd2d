#!/usr/bin/env python3
"""Appearance statistics of gel images, image folders or videos, real or rendered; see
evaluation/appearance/stats_cli.py. ``python scripts/gel_stats.py INPUT ... [--json OUT.json]``."""

import sys

from evaluation.appearance.stats_cli import main

if __name__ == "__main__":
    sys.exit(main())
