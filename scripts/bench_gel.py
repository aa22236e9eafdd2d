#!/usr/bin/env python3
"""Speed of the gel model, on one thread; see evaluation/bench/gel.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("evaluation.bench.gel", first="evaluation.common.machine_info:one_thread_env")
