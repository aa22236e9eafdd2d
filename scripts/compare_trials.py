#!/usr/bin/env python3
"""Controllers compared across insertion speed settings; see evaluation/trials/compare.py."""

import sys

from evaluation.trials.compare import main

if __name__ == "__main__":
    sys.exit(main())
