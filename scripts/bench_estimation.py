#!/usr/bin/env python3
"""Speed and field error of each estimator configuration; see evaluation/bench/estimation.py."""

import sys

from evaluation.bench.estimation import main

if __name__ == "__main__":
    sys.exit(main())
