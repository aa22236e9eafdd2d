#!/usr/bin/env python3
"""Offline torque estimation on recorded tactile frames; see evaluation/offline/estimate_cli.py."""

import sys

from evaluation.offline.estimate_cli import main

if __name__ == "__main__":
    sys.exit(main())
