#!/usr/bin/env python3
"""Speed of the simulated camera's renderer, on one thread; see evaluation/bench/render.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("evaluation.bench.render", first="evaluation.common.machine_info:one_thread_env")
