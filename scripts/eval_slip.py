#!/usr/bin/env python3
"""Score the estimator's slip flags on the simulated gel; see evaluation/experiments/slip_cli.py."""

import sys

from evaluation.experiments.slip_cli import main

if __name__ == "__main__":
    sys.exit(main())
