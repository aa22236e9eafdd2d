#!/usr/bin/env python3
"""Mini frame decoding, full vs reduced; see evaluation/bench/camera_decode.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("evaluation.bench.camera_decode")
