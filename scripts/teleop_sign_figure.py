#!/usr/bin/env python3
"""The alignment demo's sign drawing; see evaluation/teleop/sign_figure.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("evaluation.teleop.sign_figure")
