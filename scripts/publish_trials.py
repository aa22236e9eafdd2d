#!/usr/bin/env python3
"""Publish make trials' comparisons into docs/; see evaluation/trials/publish.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("evaluation.trials.publish")
