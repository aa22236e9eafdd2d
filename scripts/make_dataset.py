#!/usr/bin/env python3
"""Write a simulated calibration dataset; see evaluation/offline/make_dataset_cli.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("evaluation.offline.make_dataset_cli")
