"""Every research, figure and benchmark tool still runs (``python -m evaluation TOOL``,
evaluation/tools.py): its module's ``main`` answers ``--help``."""

import pytest

from evaluation.tools import GROUPS
from tests.script_runs import answers_help

TOOLS = [job for group in GROUPS for job in group.jobs]


@pytest.mark.parametrize("job", TOOLS, ids=lambda job: job.name)
def test_every_research_tool_answers_help(job, capsys):
    assert answers_help(job.module, capsys)
