#!/usr/bin/env python3
"""Estimators on rendered real-texture recordings; see
evaluation/real_recordings/recordings_cli.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("evaluation.real_recordings.recordings_cli")
