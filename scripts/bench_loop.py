#!/usr/bin/env python3
"""Period accuracy of the real-time control loop; see evaluation/bench/loop_period.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("evaluation.bench.loop_period")
