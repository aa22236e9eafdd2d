#!/usr/bin/env python3
"""The offline estimator demo on a synthetic sequence (``make demo``); see evaluation/demo.py."""

import sys

from evaluation.demo import main

if __name__ == "__main__":
    sys.exit(main())
