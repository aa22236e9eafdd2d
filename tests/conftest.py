"""What the whole suite shares: artifacts made once per test run and shared by the
pytest-xdist workers through a file lock in the run's common temporary folder (``made_once``):
one recorded trial, the easy scene's calibrations, and the tests' own read-only inputs; and
the order the tests start in (``LONGEST_FIRST``). The fixtures import the project when first
used: pytest-xdist's controller process, which loads this file only to hand out the tests,
starts the workers without waiting for it."""

from __future__ import annotations

import shutil
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import pytest
from filelock import FileLock

if TYPE_CHECKING:
    from controller.run.task import Task

RECORDED_TASK, RECORDED_CONTROLLER, RECORDED_SEED = "usb_c", "dipole", 0

LONGEST_FIRST = (
    "tests/evaluation/trials/test_batch.py::test_ray_gives_the_same_summary_as_local",
    "tests/controller/episode/test_episodes_doc.py::test_the_shell_snippet_runs",
    "tests/evaluation/trials/test_trial_safety.py",
    "tests/evaluation/trials/test_hole_finds.py",
    "tests/controller/episode/test_foxglove_parser.py",
    "tests/evaluation/bench/test_insertion_scene.py",
    "tests/evaluation/realgel/test_check.py",
    "tests/evaluation/trials/test_batch_stop.py",
    "tests/evaluation/trials/test_batch.py",
    "tests/evaluation/trials/test_trial.py",
    "tests/controller/cli/test_alignment_demo.py",
    "tests/controller/replay/test_episode_chart.py",
    "tests/evaluation/offline/test_dataset_calibrate.py",
    "tests/evaluation/offline/test_scene_calibration.py",
    "tests/controller/test_record.py",
    "tests/controller/replay/test_lerobot_export.py",
    "tests/evaluation/bench/test_scene_pairs.py",
)
"""Where the suite's longest tests are (whole simulated trials, batches of processes, Ray's
start, the recorded episodes' tools), longest first: they start first, so that the workers
(``--dist worksteal``, pyproject.toml) end together on short tests instead of one of them
running a long test alone at the end. Only the order changes; a test not named here runs
after them, in collection order."""


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """The tests under ``LONGEST_FIRST`` first, in its order; the rest as collected. The
    same order on every worker (pytest-xdist checks that they collected alike)."""

    def rank(item: pytest.Item) -> int:
        starts = [i for i, prefix in enumerate(LONGEST_FIRST) if item.nodeid.startswith(prefix)]
        return starts[0] if starts else len(LONGEST_FIRST)

    items.sort(key=rank)


@pytest.fixture(scope="session")
def run_root(tmp_path_factory, worker_id) -> Path:
    """The temporary folder common to every worker of this test run (each worker's own
    ``tmp_path_factory`` base lies in it; without xdist, that base itself)."""
    base = tmp_path_factory.getbasetemp()
    return base if worker_id == "master" else base.parent


def made_once(run_root: Path, name: str, make: Callable[[Path], None]) -> Path:
    """``run_root/name``, made by ``make(folder)`` by the first worker of the run to ask (the
    others wait on the lock and read it). A ``make`` that failed leaves no ``.done`` mark: the
    next one to ask starts again from an empty folder. The tests only read the folder."""
    folder = run_root / name
    with FileLock(str(run_root / f"{name}.lock")):
        if not (run_root / f"{name}.done").exists():
            shutil.rmtree(folder, ignore_errors=True)
            make(folder)
            (run_root / f"{name}.done").touch()
    return folder


def _record_trial(folder: Path) -> None:
    from controller.episode.session import EPISODE_FILE, EpisodeOptions
    from controller.run import load_task
    from evaluation.trials.trial import run

    episode = EpisodeOptions(image_format="png")
    task = load_task(RECORDED_TASK)
    outcome = run(task, RECORDED_CONTROLLER, RECORDED_SEED, out_dir=folder, episode=episode)
    assert outcome.result.success
    (folder / EPISODE_FILE).chmod(0o444)


@pytest.fixture(scope="session")
def recorded_trial(run_root) -> Path:
    """The record folder of a simulated USB-C trial (seed 0, the dipole controller) that
    inserted, with its episode recorded with lossless (PNG) frames and made read-only (the
    tools never write over their input): ``trial.json``, ``ticks.jsonl``,
    ``transitions.jsonl``, ``truth.npz``, ``episode.mcap``. Only the tests read it."""
    return made_once(run_root, "recorded_trial", _record_trial)


FELT_OVERRIDES = ("touch_spiral.rock.at_pass=0",)  # FEEL at the first touch


def _record_felt_trial(folder: Path) -> None:
    from controller.episode.session import EPISODE_FILE, EpisodeOptions
    from controller.run import load_task
    from evaluation.trials.trial import run

    task = load_task(RECORDED_TASK, FELT_OVERRIDES)
    outcome = run(task, RECORDED_CONTROLLER, RECORDED_SEED, out_dir=folder,
                  episode=EpisodeOptions())  # fmt: skip
    assert outcome.result.success and "felt" in {t.reason for t in outcome.transitions}
    (folder / EPISODE_FILE).chmod(0o444)


@pytest.fixture(scope="session")
def felt_trial(run_root) -> Path:
    """The record folder of the recorded trial's seed with FEEL rocking at the first touch
    (``FELT_OVERRIDES``): its episode holds the machine's in-hand estimates
    (``/machine/grasp_estimate``), JPEG frames; made read-only, about 10 s to record."""
    return made_once(run_root, "felt_trial", _record_felt_trial)


@pytest.fixture(scope="session")
def easy_task(run_root) -> Callable[[str], Task]:
    """``easy_task(name)``: task ``name`` on the easy scene (tests/easy_scene.py) with the
    easy scene's own calibration, fitted once per test run."""
    from tests.easy_scene import easy_scene_task, write_easy_calibration

    def task(name: str) -> Task:
        folder = made_once(run_root, f"easy_calibration_{name}",
                           lambda out: write_easy_calibration(name, out))  # fmt: skip
        return easy_scene_task(name, folder)

    return task
