#!/usr/bin/env python3
"""The live view's picture at a moment of an episode; see evaluation/teleop/screenshot.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("evaluation.teleop.screenshot")
