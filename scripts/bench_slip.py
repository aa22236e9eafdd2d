#!/usr/bin/env python3
"""Per-frame cost of the slip detector and of the estimator's push; see
evaluation/bench/slip_detection.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("evaluation.bench.slip_detection")
