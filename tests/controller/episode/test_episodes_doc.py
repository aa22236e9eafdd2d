"""Every code snippet in docs/EPISODES.md runs, as written: each ```python block in the test's
process (fresh globals) with the suite's recorded episode at the path the docs use
(out/demo/episode.mcap), each ```sh block with bash, in a temporary folder that has the
project's .venv and scripts (so `T` and `out/` are the test's own). A fenced block that is
not code is marked ```text."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

from controller.episode.session import EPISODE_FILE

ROOT = Path(__file__).resolve().parents[3]
DOC = ROOT / "docs" / "EPISODES.md"
FENCE = re.compile(r"^```(\w*)\n(.*?)^```$", re.S | re.M)


def snippets(kind: str) -> list[str]:
    return [code for lang, code in FENCE.findall(DOC.read_text()) if lang == kind]


def test_every_fenced_block_says_what_it_is():
    kinds = [lang for lang, _ in FENCE.findall(DOC.read_text())]
    assert kinds and set(kinds) <= {"python", "sh", "text"}, kinds
    assert len(snippets("python")) >= 2 and snippets("sh")


@pytest.fixture
def folder(tmp_path, recorded_trial) -> Path:
    """A folder like the project's root for the snippets: out/demo/episode.mcap (the suite's
    recorded episode), .venv and scripts (links to the project's)."""
    (tmp_path / "out" / "demo").mkdir(parents=True)
    (tmp_path / "out" / "demo" / EPISODE_FILE).symlink_to(recorded_trial / EPISODE_FILE)
    for name in ("scripts", ".venv"):
        if (ROOT / name).exists():
            (tmp_path / name).symlink_to(ROOT / name)
    return tmp_path


@pytest.mark.parametrize("index", range(len(snippets("python"))))
def test_the_python_snippet_runs(folder, index, monkeypatch):
    code = snippets("python")[index]
    monkeypatch.chdir(folder)  # in this process, with a module's fresh globals of its own
    exec(compile(code, f"{DOC.name} python block {index}", "exec"), {"__name__": "__main__"})


@pytest.mark.parametrize("index", range(len(snippets("sh"))))
def test_the_shell_snippet_runs(folder, index):
    code = snippets("sh")[index]
    if not (folder / ".venv").exists():
        pytest.fail("the shell snippets run the project's .venv (make install)")
    done = subprocess.run(
        ["bash", "-euo", "pipefail", "-c", code],
        cwd=folder, capture_output=True, text=True, timeout=1200,
    )  # fmt: skip
    assert done.returncode == 0, f"{code}\n{done.stdout}\n{done.stderr}"
    assert done.stdout.strip()
