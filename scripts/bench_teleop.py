#!/usr/bin/env python3
"""The teleop demo's view cost and unplug stop latency; see evaluation/bench/teleop_demo.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("evaluation.bench.teleop_demo")
