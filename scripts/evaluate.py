#!/usr/bin/env python3
"""Regenerate docs/EVALUATION.md and its charts; see evaluation/experiments/run.py."""

import sys

from evaluation.experiments.run import main

if __name__ == "__main__":
    sys.exit(main())
