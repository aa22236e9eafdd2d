#!/usr/bin/env python3
"""One insertion trial, simulated or on the robot; see evaluation/trials/trial_cli.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("evaluation.trials.trial_cli")
