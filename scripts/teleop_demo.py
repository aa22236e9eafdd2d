#!/usr/bin/env python3
"""The teleoperated alignment demo; see controller/cli/alignment_demo.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("controller.cli.alignment_demo")
