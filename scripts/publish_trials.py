#!/usr/bin/env python3
"""Publish make trials' comparisons into docs/; see evaluation/trials/publish.py."""

import sys

from evaluation.trials.publish import main

if __name__ == "__main__":
    sys.exit(main())
