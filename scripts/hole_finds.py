#!/usr/bin/env python3
"""Where the tip really was at each hole find; see evaluation/trials/hole_finds_cli.py."""

import sys

from evaluation.trials.hole_finds_cli import main

if __name__ == "__main__":
    sys.exit(main())
