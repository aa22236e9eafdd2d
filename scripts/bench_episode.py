#!/usr/bin/env python3
"""The episode writer's crash loss, cost and size; see evaluation/bench/episode.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("evaluation.bench.episode")
