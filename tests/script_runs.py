"""Running a tool in the test's own process: the ``main`` that ``scripts/NAME.py`` runs (its
``run_main("package.module")``), or for a research tool, the ``main`` of ``python -m
evaluation NAME`` (evaluation/tools.py). A test about the process itself (signals, exit codes
of a real process, imports) starts the command in a subprocess instead."""

from __future__ import annotations

import importlib
import re
from collections.abc import Callable
from pathlib import Path

from core.subcommands import find_job
from evaluation.tools import GROUPS

SCRIPTS = Path(__file__).resolve().parents[1] / "scripts"


def script_main(name: str) -> Callable[..., int | None]:
    """The ``main`` of the tool that ``scripts/<name>.py`` runs, or else of the research tool
    ``name`` (``python -m evaluation <name>``)."""
    script = SCRIPTS / f"{name}.py"
    if not script.is_file():
        job = find_job(GROUPS, name)
        assert job is not None, f"no scripts/{name}.py and no research tool {name}"
        return importlib.import_module(job.module).main
    module = re.search(r'run_main\(\s*"([\w.]+)"', script.read_text())
    assert module is not None, f"scripts/{name}.py does not call run_main"
    return importlib.import_module(module.group(1)).main


def exit_code(name: str, argv: list[str]) -> int:
    """The exit code of tool ``name`` (``script_main``) on ``argv`` run in this process:
    ``main``'s return value (None: 0), or the code of the SystemExit it raised (argparse's
    usage errors)."""
    try:
        code = script_main(name)(argv)
    except SystemExit as stop:
        code = stop.code
    return 0 if code is None else int(code)


def answers_help(module: str, capsys) -> bool:
    """Whether ``module``'s ``main(["--help"])``, run in this process, exits 0 with its usage
    on stdout (``capsys``: the test's capture)."""
    try:
        importlib.import_module(module).main(["--help"])
    except SystemExit as stop:
        return stop.code == 0 and "usage:" in capsys.readouterr().out
    return False
