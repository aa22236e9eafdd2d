#!/usr/bin/env python3
"""The teleoperated alignment demo; see evaluation/teleop/demo_cli.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("evaluation.teleop.demo_cli")
