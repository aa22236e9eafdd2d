#!/usr/bin/env python3
"""Estimators on real gel textures under an independent elastic model; see
evaluation/realgel/check_cli.py."""

import sys

from evaluation.realgel.check_cli import main

if __name__ == "__main__":
    sys.exit(main())
