#!/usr/bin/env python3
"""Controllers compared across insertion speed settings; see evaluation/trials/compare.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("evaluation.trials.compare")
