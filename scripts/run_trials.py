#!/usr/bin/env python3
"""A batch of simulated insertion trials; see evaluation/trials/batch_cli.py."""

import sys

from evaluation.trials.batch_cli import main

if __name__ == "__main__":
    sys.exit(main())
