#!/usr/bin/env python3
"""Where trials spend their time, rule by rule; see evaluation/trials/where_time_goes.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("evaluation.trials.where_time_goes")
