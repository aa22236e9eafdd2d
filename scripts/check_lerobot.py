#!/usr/bin/env python3
"""Load a LeRobot export with the real ``lerobot`` and check every frame (``make
check-lerobot``); see evaluation/episodes/lerobot_check.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("evaluation.episodes.lerobot_check")
