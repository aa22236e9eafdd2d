#!/usr/bin/env python3
"""Score the estimator's slip flags on the simulated gel; see evaluation/experiments/slip_cli.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("evaluation.experiments.slip_cli")
