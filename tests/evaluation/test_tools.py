"""Every research, figure and benchmark tool still runs (``python -m evaluation TOOL``,
evaluation/tools.py): its module's ``main`` answers ``--help``."""

import importlib

import pytest

from evaluation.tools import GROUPS

TOOLS = [job for group in GROUPS for job in group.jobs]


@pytest.mark.parametrize("job", TOOLS, ids=lambda job: job.name)
def test_every_research_tool_answers_help(job, capsys):
    main = importlib.import_module(job.module).main
    with pytest.raises(SystemExit) as stop:
        main(["--help"])
    assert stop.value.code == 0
    assert "usage:" in capsys.readouterr().out
