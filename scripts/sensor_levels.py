#!/usr/bin/env python3
"""The insertion scene's camera effects against the real captures; see
evaluation/scene/sensor_levels.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("evaluation.scene.sensor_levels")
