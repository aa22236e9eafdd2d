#!/usr/bin/env python3
"""Speed of the simulated insertion scene on one thread; evaluation/bench/insertion_scene.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main(
        "evaluation.bench.insertion_scene",
        first="evaluation.common.machine_info:one_thread_env",
    )
