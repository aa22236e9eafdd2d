"""``python -m evaluation TOOL [ARGS ...]``: the research, figure and benchmark tools
(evaluation/tools.py)."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("evaluation.tools")
