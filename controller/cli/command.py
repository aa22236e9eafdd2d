"""``tactile``: the product's one command, a subcommand per job (``tactile --help`` lists
them by job; ``tactile JOB --help`` gives the job's options).

Each job is a tool's module, named here and imported only when chosen (core/subcommands.py): the
help loads no numerical library, and a job on the robot never loads the simulator. The jobs
that exist only in simulation (a batch of trials, a comparison) are tools of evaluation/,
named here by their module as the device registry names the simulator's drivers. Installed
as the ``tactile`` command (pyproject's ``[project.scripts]``: ``run``); also
``python -m controller.cli.command``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NoReturn

from core.entry_point import run_main
from core.subcommands import Group, Job, dispatch

DESCRIPTION = "Insert a USB plug into its port by feel, with a visuotactile sensor."

GROUPS = (
    Group(
        "insertion trials",
        (
            Job("trial", "controller.cli.trial_cli",
                "one insertion trial, simulated (default) or on the robot (--backend real)"),
            Job("trials", "evaluation.trials.batch_cli", "a batch of simulated trials"),
            Job("compare", "evaluation.trials.compare",
                "controllers compared across insertion speeds, in simulation"),
        ),
    ),
    Group(
        "teleop demo",
        (
            Job("teleop", "controller.cli.alignment_demo",
                "the teleoperated alignment demo, simulated or on the robot"),
        ),
    ),
    Group(
        "episodes",
        (
            Job("replay", "controller.cli.replay",
                "an episode's summary | plot | reestimate | export | repair"),
        ),
    ),
    Group(
        "sensor and estimator",
        (
            Job("estimate", "controller.cli.estimate",
                "torques estimated offline on recorded tactile frames or a video"),
            Job("calibrate", "controller.cli.calibrate",
                "the estimator's calibration fitted on a dataset"),
        ),
    ),
    Group(
        "hardware",
        (Job("check-hardware", "drivers.check_hardware", "check the configured devices"),),
    ),
)  # fmt: skip
"""The jobs, by what a user does."""


def main(argv: Sequence[str] | None = None) -> int | None:
    """Run the job ``argv`` names (default ``sys.argv[1:]``); its exit code."""
    return dispatch("tactile", DESCRIPTION, GROUPS, argv)


def run() -> NoReturn:
    """The installed ``tactile`` command."""
    run_main("controller.cli.command")


if __name__ == "__main__":  # python -m controller.cli.command
    run()
