"""Foxglove's own parsers read every channel of a recorded episode (through Node).

tests/node/foxglove_parser/ is a small npm package, pinned by its package-lock.json, that
takes Foxglove Studio's ``parseChannel`` and ``parseJsonSchema`` (packages/mcap-support of the
open-source Studio, which Lichtblick forked) out of the published ``@foxglove/studio-base``
1.48.0 and runs them on the episode: every channel must parse and every message decode, every
path the layout plots must be a number (see check_episode.mjs). ``npm ci`` installs it once
per version of the package's files into the user's cache folder (the npm registry is the only
network use).
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import subprocess
import tempfile
from pathlib import Path

import pytest
from filelock import FileLock

from controller.episode import read_episode
from controller.episode.session import EPISODE_FILE
from controller.episode.topics import JSON_SCHEMAS

PACKAGE = Path(__file__).resolve().parents[2] / "node" / "foxglove_parser"
LAYOUT = Path(__file__).resolve().parents[3] / "docs" / "foxglove" / "episode_layout.json"


FILES = ("package.json", "package-lock.json", "check_episode.mjs")


def _install(folder: Path, npm: str) -> None:
    """``npm ci`` of the package into ``folder`` (new), with its own npm cache."""
    folder.mkdir(parents=True)
    for name in FILES:
        shutil.copy(PACKAGE / name, folder / name)
    cache = folder / "npm-cache"
    env = {**os.environ, "npm_config_cache": str(cache), "npm_config_update_notifier": "false"}
    done = subprocess.run(
        [npm, "ci", "--ignore-scripts", "--no-audit", "--no-fund", "--cache", str(cache)],
        cwd=folder, env=env, capture_output=True, text=True, timeout=900,
    )  # fmt: skip
    assert done.returncode == 0, f"npm ci failed:\n{done.stdout}\n{done.stderr}"
    shutil.rmtree(cache)


@pytest.fixture(scope="module")
def checker() -> Path:
    """The package installed (``npm ci``) once per version of its files, in the user's cache
    folder (``$XDG_CACHE_HOME``, else ~/.cache), keyed by their SHA-256: its check script's
    path. A clean machine installs it from scratch; an install cut short is done again."""
    npm, node = shutil.which("npm"), shutil.which("node")
    assert npm and node, "this test needs Node.js and npm on PATH (Node 20)"
    key = hashlib.sha256(b"".join((PACKAGE / name).read_bytes() for name in FILES))
    root = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "tactile-insertion"
    root.mkdir(parents=True, exist_ok=True)
    folder = root / f"foxglove_parser-{key.hexdigest()[:16]}"
    with FileLock(str(folder) + ".lock"):
        if not folder.is_dir():
            partial = Path(tempfile.mkdtemp(prefix="foxglove_parser-", dir=root))
            try:
                _install(partial / "package", npm)
                (partial / "package").rename(folder)
            finally:
                shutil.rmtree(partial)
    return folder / "check_episode.mjs"


def _check(script: Path, *args: str | Path) -> tuple[int, dict]:
    done = subprocess.run(
        [shutil.which("node") or "node", str(script), *map(str, args)],
        capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert done.stdout.strip(), done.stderr
    return done.returncode, json.loads(done.stdout)


def test_foxglove_parses_every_channel_and_plots_numbers(checker, recorded_trial, tmp_path):
    episode = recorded_trial / EPISODE_FILE
    schemas = tmp_path / "schemas.json"
    schemas.write_text(json.dumps(JSON_SCHEMAS))
    code, report = _check(checker, episode, LAYOUT, schemas)
    assert code == 0 and report["problems"] == [], report["problems"]
    assert "@foxglove/studio-base" in report["parser"]
    assert report["schemas"] == len(JSON_SCHEMAS)
    assert report["channels"] == read_episode(episode).counts  # every channel, every message
    plotted = report["plotted"]
    for field in ("tau_x", "tau_y", "tau_z", "shear_x", "shear_y", "normal"):
        assert plotted[f"/tactile/wrench.{field}"]["type"] == "float64"
        assert plotted[f"/tactile/wrench.{field}"]["present"] > 0
    assert plotted["/loop/tick.phase"]["present"] == report["channels"]["/loop/tick"]
    assert "/teleop/input.in_control_by" in plotted


def test_foxglove_parses_the_in_hand_estimates_channel(checker, felt_trial, tmp_path):
    """A trial whose machine estimated the plug in the hand: its ``/machine/grasp_estimate``
    channel parses and every message decodes, as the others."""
    episode = felt_trial / EPISODE_FILE
    schemas = tmp_path / "schemas.json"
    schemas.write_text(json.dumps(JSON_SCHEMAS))
    code, report = _check(checker, episode, LAYOUT, schemas)
    assert code == 0 and report["problems"] == [], report["problems"]
    assert report["channels"] == read_episode(episode).counts
    assert report["channels"]["/machine/grasp_estimate"] >= 1


def test_the_parser_rejects_what_foxglove_drops(checker, tmp_path):
    """The check is live: the schema forms the old episodes had are refused, as in the app."""
    bad = {
        "a": {"type": "object", "properties": {"tau_x": {"type": ["number", "null"]}}},
        "b": {"type": "object", "properties": {"call": {"enum": ["push"]}}},
        "c": {"type": "object", "properties": {"v": {"anyOf": [{"type": "array"}]}}},
        "ok": {"type": "object", "properties": {"call": {"type": "string", "enum": ["push"]}}},
    }
    schemas = tmp_path / "bad.json"
    schemas.write_text(json.dumps(bad))
    code, report = _check(checker, "-", "-", schemas)
    assert code == 1 and report["schemas"] == 1
    assert [p.split(":")[0] for p in report["problems"]] == ["schema a", "schema b", "schema c"]
    assert 'Unsupported type ["number","null"] for tau_x' in report["problems"][0]
