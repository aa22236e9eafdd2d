#!/usr/bin/env python3
"""Regenerate docs/EVALUATION.md and its charts; see evaluation/experiments/run.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("evaluation.experiments.run")
