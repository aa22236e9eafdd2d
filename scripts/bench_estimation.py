#!/usr/bin/env python3
"""Speed and field error of each estimator configuration; see evaluation/bench/estimation.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("evaluation.bench.estimation")
