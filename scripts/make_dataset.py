#!/usr/bin/env python3
"""Write a simulated calibration dataset; see evaluation/offline/make_dataset_cli.py."""

import sys

from evaluation.offline.make_dataset_cli import main

if __name__ == "__main__":
    sys.exit(main())
