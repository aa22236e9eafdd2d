#!/usr/bin/env python3
"""Mini frame decoding, full vs reduced; see evaluation/bench/camera_decode.py."""

import sys

from evaluation.bench.camera_decode import main

if __name__ == "__main__":
    sys.exit(main())
