"""The one installed command, ``tactile``: a subcommand per job that hands the rest of the
command line to its tool (controller/cli/command.py, core/subcommands.py), from a module light
enough that a signal while the tool loads is handled; the research tools behind ``python -m
evaluation`` (evaluation/tools.py) the same way."""

import importlib
import importlib.util
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from controller.cli import command
from core import subcommands
from evaluation import tools
from tests.script_runs import answers_help

ROOT = Path(__file__).resolve().parents[3]
JOBS = [job for group in command.GROUPS for job in group.jobs]
TOOLS = [job for group in tools.GROUPS for job in group.jobs]


def run(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, *args], capture_output=True, text=True, cwd=ROOT)


def test_the_one_installed_command_is_tactile():
    commands = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]
    assert commands == {"tactile": "controller.cli.command:run"}


def test_each_job_and_tool_names_a_module_with_a_main():
    names = [job.name for job in JOBS + TOOLS]
    assert len(names) == len(set(names))
    assert {"trial", "trials", "compare", "teleop", "replay", "estimate", "calibrate",
            "check-hardware"} <= {job.name for job in JOBS}  # fmt: skip
    for job in JOBS + TOOLS:
        assert importlib.util.find_spec(job.module) is not None, job.name
        assert re.search(r"^def main\(", importlib.util.find_spec(job.module).loader
                         .get_source(job.module), re.M), job.name  # fmt: skip


def test_scripts_hold_only_the_product_jobs():
    scripts = sorted((ROOT / "scripts").glob("*.py"))
    assert len(scripts) <= 10
    for script in scripts:
        module = re.search(r'run_main\("([\w.]+)"\)', script.read_text()).group(1)
        assert module == "controller.cli.command" or module in {job.module for job in JOBS}


def test_the_help_lists_every_job_by_group():
    done = run("-m", "controller.cli.command", "--help")
    assert done.returncode == 0 and done.stderr == ""
    for group in command.GROUPS:
        assert f"\n{group.title}:\n" in done.stdout
        for job in group.jobs:
            assert re.search(rf"^  {re.escape(job.name)} +\S", done.stdout, re.M), job.name


@pytest.mark.parametrize("argv", [[], ["tiral", "--task", "usb_c"]])
def test_no_job_or_an_unknown_one_is_one_line_and_exit_2(argv):
    done = run("-m", "controller.cli.command", *argv)
    assert done.returncode == 2 and done.stdout == ""
    assert done.stderr.startswith("tactile: error: ") and done.stderr.count("\n") == 1
    assert "trial, trials, compare" in done.stderr


def test_a_job_gets_the_rest_of_the_command_line():
    argv = ["trial", "--task", "usb_c", "--seed", "-1", "--out", "o"]
    done = run("-m", "controller.cli.command", *argv)
    assert done.returncode == 2 and "Traceback" not in done.stderr  # the tool's parser's
    assert done.stderr.splitlines()[-1].startswith("tactile trial: error: argument --seed")
    assert done.stderr.startswith("usage: tactile trial ")


def test_the_research_tools_answer_help():
    done = run("-m", "evaluation", "--help")
    assert done.returncode == 0
    assert all(job.name in done.stdout for job in TOOLS)
    done = run("-m", "evaluation", "bench_gel", "--steps", "0")
    assert done.returncode == 2 and "--steps" in done.stderr and "Traceback" not in done.stderr


@pytest.mark.parametrize(
    "module", ["controller.cli.command", "evaluation.tools", "the command run as main"]
)
def test_the_commands_module_loads_no_heavy_library(module):
    code = f"import sys; sys.argv = ['x', '--help']; import {module}; print(sorted(sys.modules))"
    if module == "the command run as main":  # python -m controller.cli.command --help
        code = (
            "import runpy, sys; sys.argv = ['tactile', '--help']\n"
            "try:\n    runpy.run_module('controller.cli.command', run_name='__main__')\n"
            "except SystemExit:\n    pass\nprint(sorted(sys.modules))"
        )
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                            cwd=ROOT, check=True).stdout  # fmt: skip
    for heavy in ("'numpy'", "'cv2'", "'mujoco'", "'evaluation.trials'", "'drivers.sim'"):
        assert heavy not in loaded


def test_the_product_names_evaluation_modules_only_where_a_simulated_job_is_chosen():
    """The product never imports evaluation/ (tests/test_layers.py); the command table and
    the trial's simulated backend name a module of it, imported only when chosen."""
    naming = {
        str(path.relative_to(ROOT))
        for path in (ROOT / "controller").rglob("*.py")
        if re.search(r'"evaluation\.[\w.]+"', path.read_text())
    }
    assert naming == {"controller/cli/command.py", "controller/cli/trial_cli.py"}


def test_the_trial_command_offers_the_trial_tools_controllers():
    from controller.cli import trial_cli
    from controller.run import CONTROLLERS
    from evaluation.trials.oracle import TRIAL_CONTROLLERS

    assert [*CONTROLLERS, *trial_cli.SIM_ONLY_CONTROLLERS] == list(TRIAL_CONTROLLERS)
    assert importlib.util.find_spec(trial_cli.SIMULATION) is not None


@pytest.mark.parametrize("job", JOBS, ids=lambda job: job.name)
def test_every_job_answers_help(job, capsys):
    assert answers_help(job.module, capsys)


def _usage(main, name: str, monkeypatch, capsys) -> str:
    """The first line of ``main([name, "--help"])``'s output, run as the command runs it."""
    monkeypatch.setattr(sys, "argv", list(sys.argv))  # dispatch sets them for the job
    monkeypatch.setattr(subcommands, "_running", None)
    with pytest.raises(SystemExit) as stop:
        main([name, "--help"])
    assert stop.value.code == 0
    return capsys.readouterr().out.splitlines()[0]


@pytest.mark.parametrize("job", JOBS, ids=lambda job: job.name)
def test_every_job_s_usage_names_the_command_and_the_job(job, monkeypatch, capsys):
    assert _usage(command.main, job.name, monkeypatch, capsys).startswith(
        f"usage: tactile {job.name} "
    )


@pytest.mark.parametrize("tool", TOOLS, ids=lambda tool: tool.name)
def test_every_research_tool_s_usage_names_python_m_evaluation(tool, monkeypatch, capsys):
    assert _usage(tools.main, tool.name, monkeypatch, capsys).startswith(
        f"usage: python -m evaluation {tool.name}"
    )
