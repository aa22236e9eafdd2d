#!/usr/bin/env python3
"""Episode tools (summary, plot, reestimate, export to LeRobot, repair); see
evaluation/episodes/replay_cli.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("evaluation.episodes.replay_cli")
