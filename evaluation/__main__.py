"""``python -m evaluation TOOL [ARGS ...]``: the research, figure and benchmark tools
(evaluation/tools.py)."""

from core.entry_point import run_main

run_main("evaluation.tools")
