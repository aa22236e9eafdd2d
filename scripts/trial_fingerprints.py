#!/usr/bin/env python3
"""Digests of what simulated trials decided, per seed; evaluation/bench/trial_fingerprints.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main(
        "evaluation.bench.trial_fingerprints",
        first="evaluation.common.machine_info:one_thread_env",
    )
