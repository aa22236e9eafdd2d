"""A command with one subcommand per job (``tactile trial ...``, ``python -m evaluation
bench_gel ...``): the job's name picks a tool's module, and the rest of the command line goes
to that module's own ``main`` (its argparse parser: its ``--help``, its errors, its exit
codes). Only the chosen tool's module is imported, so ``--help`` is fast and a job on the
robot never loads what another job needs (the simulator). Importing this module loads only
the standard library.

The process runs through ``core.entry_point.run_main`` (Ctrl-C and SIGTERM end it with one
line at any moment, the tool's imports included): an installed command's function is
``run_main("<this table's module>")``, whose ``main`` is ``dispatch``.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Sequence
from dataclasses import dataclass

from core.entry_point import silence_closed_stdout

EXIT_USAGE = 2
"""The exit code of a command line the command cannot read (argparse's)."""

_running: str | None = None
"""``PROG JOB`` while ``dispatch`` runs a job, else None (``job_prog`` reads it)."""


def job_prog(name: str) -> str:
    """The name a tool's parser shows in its usage line: ``PROG JOB`` (``tactile trial``,
    ``python -m evaluation bench_gel``) when ``dispatch`` runs it, else the tool's own
    ``name`` (its script, or its ``main`` called directly)."""
    return _running or name


@dataclass(frozen=True)
class Job:
    """One subcommand: its ``name`` on the command line, the tool's ``module`` (whose
    ``main(argv=None)`` reads ``sys.argv[1:]``), a one-line ``summary`` for the help, and
    ``first``: ``"module:function"`` to call before the tool's module is imported (e.g. to
    limit the threads of the numerical libraries it loads), or None."""

    name: str
    module: str
    summary: str
    first: str | None = None


@dataclass(frozen=True)
class Group:
    """Jobs listed together in the help, under ``title``."""

    title: str
    jobs: tuple[Job, ...]


def find_job(groups: Sequence[Group], name: str) -> Job | None:
    """The job called ``name``, or None."""
    return next((job for group in groups for job in group.jobs if job.name == name), None)


def help_text(prog: str, description: str, groups: Sequence[Group]) -> str:
    """The command's help: its usage, ``description`` and the jobs by group."""
    width = max(len(job.name) for group in groups for job in group.jobs) + 2
    lines = [f"usage: {prog} JOB [ARGS ...]    ({prog} JOB --help: the job's options)", ""]
    lines += [description, ""]
    for group in groups:
        lines.append(f"{group.title}:")
        lines += [f"  {job.name:<{width}}{job.summary}" for job in group.jobs]
    return "\n".join(lines)


def dispatch(
    prog: str, description: str, groups: Sequence[Group], argv: Sequence[str] | None = None
) -> int | None:
    """Run the job that ``argv`` (default ``sys.argv[1:]``) names with the rest of it, as
    ``PROG JOB`` (its ``sys.argv``): the tool's ``main()`` result. ``-h``/``--help``: the
    help on stdout, 0; no job or an unknown one: one line on stderr, exit 2."""
    args = list(sys.argv[1:] if argv is None else argv)
    if args and args[0] in ("-h", "--help"):
        try:
            print(help_text(prog, description, groups), flush=True)
        except BrokenPipeError:  # the reader left (``| head``): quietly, as SIGPIPE would
            silence_closed_stdout()
        return 0
    job = find_job(groups, args[0]) if args else None
    if job is None:
        names = ", ".join(job.name for group in groups for job in group.jobs)
        said = f"unknown job '{args[0]}'" if args else "no job given"
        print(f"{prog}: error: {said}; expected one of: {names} ({prog} --help)",
              file=sys.stderr)  # fmt: skip
        return EXIT_USAGE
    global _running
    _running = f"{prog} {job.name}"
    sys.argv = [_running, *args[1:]]
    if job.first is not None:
        first_module, function = job.first.split(":")
        getattr(importlib.import_module(first_module), function)()
    result: int | None = importlib.import_module(job.module).main()
    return result
