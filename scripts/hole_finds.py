#!/usr/bin/env python3
"""Where the tip really was at each hole find; see evaluation/trials/hole_finds_cli.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("evaluation.trials.hole_finds_cli")
