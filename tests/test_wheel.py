"""The product as a user installs it: the wheel built, installed into a fresh venv with its
dependencies, and its command, ``tactile``, run from a folder outside the checkout (the configs
are package data, found through importlib.resources, not through the source tree).

Slow (it installs the dependencies into a new venv); ``.ci/run`` runs it.
"""

from __future__ import annotations

import csv
import shutil
import subprocess
import sys
import venv
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
REAL_GEL = ROOT / "drivers" / "sim" / "render" / "real_gels" / "gelsight_markers_a.png"

NOT_SOURCE = (".git", ".venv", "build", "out", "*.egg-info", "__pycache__", ".*_cache")

pytestmark = pytest.mark.slow


def run(command: list[str], cwd: Path, timeout_s: float = 900.0) -> subprocess.CompletedProcess:
    done = subprocess.run(command, cwd=cwd, capture_output=True, text=True, timeout=timeout_s)
    assert done.returncode == 0, f"{command}: exit {done.returncode}\n{done.stderr[-3000:]}"
    return done


@pytest.fixture(scope="module")
def installed(tmp_path_factory) -> Path:
    """The bin/ folder of a fresh venv holding the wheel and its dependencies."""
    work = tmp_path_factory.mktemp("wheel")
    source = work / "source"  # a clean copy: no stale build/ of an earlier tree
    shutil.copytree(ROOT, source, ignore=shutil.ignore_patterns(*NOT_SOURCE))
    run([sys.executable, "-m", "pip", "wheel", str(source), "--no-deps", "-q", "-w",
         str(work / "dist")], cwd=work)  # fmt: skip
    (wheel,) = (work / "dist").glob("tactile_insertion-*.whl")
    venv.create(work / "venv", with_pip=True)
    bin_dir = work / "venv" / "bin"
    run([str(bin_dir / "python"), "-m", "pip", "install", "-q", str(wheel)], cwd=work)
    return bin_dir


def test_the_installed_package_is_not_the_checkout(installed, tmp_path):
    code = "import controller, configs; print(controller.__file__); print(configs.__file__)"
    out = run([str(installed / "python"), "-c", code], cwd=tmp_path).stdout
    assert str(ROOT) not in out and str(installed.parent) in out


def test_a_one_seed_trial_runs_from_outside_the_checkout(installed, tmp_path):
    out = tmp_path / "trial"
    done = run([str(installed / "tactile"), "trial", "--task", "usb_c", "--seed", "0",
                "--out", str(out)], cwd=tmp_path)  # fmt: skip
    assert "outcome: INSERTED" in done.stdout
    assert (out / "trial.json").is_file() and (out / "ticks.jsonl").stat().st_size > 0
    episode = str(out / "episode.mcap")
    summary = run([str(installed / "tactile"), "replay", "summary", episode], cwd=tmp_path)
    assert "file: complete" in summary.stdout and "/tactile/image" in summary.stdout
    dataset = tmp_path / "lerobot"
    run([str(installed / "tactile"), "replay", "export", episode, "--lerobot", str(dataset)],
        cwd=tmp_path)  # fmt: skip
    assert (dataset / "videos" / "observation.images.tactile" / "chunk-000").is_dir()
    assert (dataset / "meta" / "info.json").is_file()


def test_an_offline_estimate_runs_from_outside_the_checkout(installed, tmp_path):
    import cv2

    frames = tmp_path / "frames"
    frames.mkdir()
    image = cv2.imread(str(REAL_GEL))
    for k in range(6):  # the gel, then shifted by up to 2 px: a field to estimate
        cv2.imwrite(str(frames / f"{k:03d}.png"), np.roll(image, k // 3, axis=1))
    out = tmp_path / "estimates.csv"
    run([str(installed / "tactile"), "estimate", str(frames), "--reference", "0",
         "--out", str(out)], cwd=tmp_path)  # fmt: skip
    with out.open() as handle:
        rows = list(csv.DictReader(line for line in handle if not line.startswith("#")))
    assert len(rows) == 6 and {"tau_x", "tau_y", "tau_z"} <= set(rows[0])


def test_tactile_lists_every_job_and_each_job_answers_help(installed, tmp_path):
    from controller.cli.command import GROUPS

    listed = run([str(installed / "tactile"), "--help"], cwd=tmp_path, timeout_s=120.0).stdout
    for job in (job for group in GROUPS for job in group.jobs):
        assert f"  {job.name} " in listed, job.name
        done = run([str(installed / "tactile"), job.name, "--help"], cwd=tmp_path,
                   timeout_s=120.0)  # fmt: skip
        assert "usage:" in done.stdout, job.name
    done = run([str(installed / "python"), "-m", "evaluation", "--help"], cwd=tmp_path)
    assert "bench_gel" in done.stdout
