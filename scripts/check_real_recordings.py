#!/usr/bin/env python3
"""Estimators on rendered real-texture recordings; see
evaluation/real_recordings/recordings_cli.py."""

import sys

from evaluation.real_recordings.recordings_cli import main

if __name__ == "__main__":
    sys.exit(main())
