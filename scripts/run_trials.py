#!/usr/bin/env python3
"""A batch of simulated insertion trials; see evaluation/trials/batch_cli.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("evaluation.trials.batch_cli")
