#!/usr/bin/env python3
"""The true gel torques during the search against the wrist's stiffness; see
evaluation/scene/search_torques.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("evaluation.scene.search_torques")
