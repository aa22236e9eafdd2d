#!/usr/bin/env python3
"""Estimators on real gel textures under an independent elastic model; see
evaluation/realgel/cli.py."""

import sys

from evaluation.realgel.cli import main

if __name__ == "__main__":
    sys.exit(main())
