#!/usr/bin/env python3
"""Per-frame cost of the slip detector and of the estimator's push; see
evaluation/bench/slip_detection.py."""

import sys

from evaluation.bench.slip_detection import main

if __name__ == "__main__":
    sys.exit(main())
