#!/usr/bin/env python3
"""The dipole's origin under pushing, on the true field; see evaluation/realgel/origins_cli.py."""

import sys

from evaluation.realgel.origins_cli import main

if __name__ == "__main__":
    sys.exit(main())
