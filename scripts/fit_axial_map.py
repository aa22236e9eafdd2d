#!/usr/bin/env python3
"""The touch spiral's axial-force map; see evaluation/trials/axial_map_cli.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("evaluation.trials.axial_map_cli")
