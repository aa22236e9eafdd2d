#!/usr/bin/env python3
"""Appearance statistics of gel images, image folders or videos, real or rendered; see
evaluation/appearance/stats_cli.py. ``python scripts/gel_stats.py INPUT ... [--json OUT.json]``."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("evaluation.appearance.stats_cli")
