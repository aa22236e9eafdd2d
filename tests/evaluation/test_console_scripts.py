"""The installed commands run the same tools as scripts/, through run_main, from a module
light enough that a signal while the tool loads is handled (evaluation/console_scripts.py)."""

import re
import subprocess
import sys
import tomllib
from pathlib import Path

from evaluation import console_scripts

ROOT = Path(__file__).resolve().parents[2]


def test_each_command_runs_the_tool_of_its_script():
    commands = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]
    assert len(commands) == len(console_scripts.TOOLS) == 8
    for command, target in commands.items():
        name = command.removeprefix("tactile-").replace("-", "_")
        assert target == f"evaluation.console_scripts:{name}" and callable(
            getattr(console_scripts, name)
        )
        script = (ROOT / "scripts" / f"{name}.py").read_text()
        assert re.search(rf'run_main\("{re.escape(console_scripts.TOOLS[name])}"\)', script)


def test_the_commands_module_loads_no_heavy_library():
    code = "import sys, evaluation.console_scripts; print(sorted(sys.modules))"
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                            cwd=ROOT, check=True).stdout  # fmt: skip
    for heavy in ("'numpy'", "'cv2'", "'mujoco'", "'controller'"):
        assert heavy not in loaded
