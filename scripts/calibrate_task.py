#!/usr/bin/env python3
"""Fit a task's calibration in its simulated scene; see evaluation/offline/calibrate_task_cli.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("evaluation.offline.calibrate_task_cli")
