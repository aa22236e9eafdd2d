#!/usr/bin/env python3
"""One insertion trial, simulated or on the robot; see evaluation/trials/trial_cli.py."""

import sys

from evaluation.trials.trial_cli import main

if __name__ == "__main__":
    sys.exit(main())
