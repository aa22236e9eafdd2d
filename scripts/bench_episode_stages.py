#!/usr/bin/env python3
"""The episode writer thread's CPU by stage and topic; see evaluation/bench/episode_stages.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("evaluation.bench.episode_stages")
