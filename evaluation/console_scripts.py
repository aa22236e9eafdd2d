"""The installed commands (pyproject's ``[project.scripts]``): each runs its tool as its
script in scripts/ does, through ``core.entry_point.run_main``, so Ctrl-C or SIGTERM while
the tool's modules import ends with one line too. This module imports only the standard
library and ``core.entry_point``."""

from __future__ import annotations

from typing import NoReturn

from core.entry_point import run_main

TOOLS = {
    "run_trial": "evaluation.trials.trial_cli",
    "run_trials": "evaluation.trials.batch_cli",
    "compare_trials": "evaluation.trials.compare",
    "estimate": "evaluation.offline.estimate_cli",
    "calibrate": "evaluation.offline.calibrate_cli",
    "check_hardware": "drivers.check_hardware",
    "replay": "evaluation.episodes.replay_cli",
    "teleop_demo": "evaluation.teleop.demo_cli",
}
"""Script name (scripts/NAME.py, command ``tactile-NAME`` with dashes) -> the tool's module."""


def run_trial() -> NoReturn:
    run_main(TOOLS["run_trial"])


def run_trials() -> NoReturn:
    run_main(TOOLS["run_trials"])


def compare_trials() -> NoReturn:
    run_main(TOOLS["compare_trials"])


def estimate() -> NoReturn:
    run_main(TOOLS["estimate"])


def calibrate() -> NoReturn:
    run_main(TOOLS["calibrate"])


def check_hardware() -> NoReturn:
    run_main(TOOLS["check_hardware"])


def replay() -> NoReturn:
    run_main(TOOLS["replay"])


def teleop_demo() -> NoReturn:
    run_main(TOOLS["teleop_demo"])
