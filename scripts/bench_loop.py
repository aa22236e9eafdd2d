#!/usr/bin/env python3
"""Period accuracy of the real-time control loop; see evaluation/bench/loop_period.py."""

import sys

from evaluation.bench.loop_period import main

if __name__ == "__main__":
    sys.exit(main())
