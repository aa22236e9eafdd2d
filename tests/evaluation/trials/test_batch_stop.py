"""A batch stopped by SIGINT, SIGTERM (to the process or its group) or SIGKILL: it stops at
once, leaves no process behind, and its records, trials.csv and summary agree."""

from __future__ import annotations

import csv
import json
import os
import signal
import subprocess
import sys
import time
import tracemalloc
from pathlib import Path

import pytest

from evaluation.trials.batch import CSV_NAME, SUMMARY_NAME
from evaluation.trials.batch_cli import main as batch_main
from tests.evaluation.trials.fake_trials import PIDS, long_trial

ROOT = Path(__file__).resolve().parents[3]
TRIALS = long_trial.__module__  # the trial functions by name (--trial-function)
RUN_TRIALS = (
    "import sys; from evaluation.trials.batch_cli import main; sys.exit(main(sys.argv[1:]))"
)
STOP_WITHIN_S = 2.0
GONE_WITHIN_S = 5.0


def _descendants(pid: int) -> set[int]:
    """Every process below ``pid`` (Linux /proc)."""
    children: dict[int, list[int]] = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        children.setdefault(int(fields[1]), []).append(int(stat.parent.name))
    found, todo = set(), [pid]
    while todo:
        for child in children.get(todo.pop(), []):
            found.add(child)
            todo.append(child)
    return found


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"  # a zombie has ended; only its exit status is left


def _assert_gone(pids: set[int]) -> None:
    deadline = time.monotonic() + GONE_WITHIN_S
    while time.monotonic() < deadline and any(_alive(p) for p in pids):
        time.sleep(0.05)
    assert not [p for p in pids if _alive(p)], "processes left behind"


def _start(tmp_path: Path, workers: int, seeds: str = "0:6") -> tuple[subprocess.Popen, Path]:
    out, pids = tmp_path / "out", tmp_path / "pids"
    pids.mkdir()
    process = subprocess.Popen(
        [
            sys.executable,
            "-c",
            RUN_TRIALS,
            "--task",
            "usb_c",
            "--seeds",
            seeds,
            "--workers",
            str(workers),
            "--records",
            "--out",
            str(out),
            "--trial-function",
            f"{TRIALS}:long_trial",
        ],  # fmt: skip
        cwd=ROOT,
        env={**os.environ, "PYTHONPATH": str(ROOT), PIDS: str(pids)},
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,  # its own process group, to signal the group
    )
    # seed 0 finished and recorded; every worker busy with a long trial
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and not (
        len(list(pids.iterdir())) == 1 + workers and _rows(out) == 1
    ):
        time.sleep(0.05)
    assert len(list(pids.iterdir())) == 1 + workers and _rows(out) == 1
    return process, out


def _rows(out: Path) -> int:
    try:
        with (out / CSV_NAME).open(newline="") as handle:
            return len(list(csv.DictReader(handle)))
    except FileNotFoundError:
        return 0


@pytest.mark.parametrize(
    ("workers", "signum", "to_group", "times"),
    [
        (1, signal.SIGINT, False, 1),
        (1, signal.SIGTERM, True, 1),
        (2, signal.SIGTERM, False, 1),
        (2, signal.SIGINT, True, 1),
        (2, signal.SIGINT, False, 2),  # a second Ctrl-C changes nothing
    ],
)
def test_a_signal_stops_the_batch_at_once_leaving_no_process_and_agreeing_files(
    tmp_path, workers, signum, to_group, times
):
    process, out = _start(tmp_path, workers)
    below = _descendants(process.pid)
    sent = time.monotonic()
    for _ in range(times):
        if to_group:
            os.killpg(process.pid, signum)
        else:
            process.send_signal(signum)
    _, err = process.communicate(timeout=30)
    took = time.monotonic() - sent
    assert process.returncode == 128 + signum, err
    assert took < STOP_WITHIN_S, f"stopped {took:.1f} s after the signal"
    assert "Traceback" not in err
    assert f"interrupted by {signal.Signals(signum).name} after 1 of 6 trials" in err
    _assert_gone(below)
    summary = json.loads((out / SUMMARY_NAME).read_text())
    assert summary["n"] == _rows(out) == 1 and summary["complete"] is False
    assert sorted(p.name for p in (out / "records").iterdir()) == ["dipole-0"]


def test_a_batch_killed_with_sigkill_leaves_no_worker(tmp_path):
    process, out = _start(tmp_path, 2)
    below = _descendants(process.pid)
    assert len(below) >= 2  # the two workers (and multiprocessing's resource tracker)
    process.kill()
    process.communicate(timeout=10)
    _assert_gone(below)


@pytest.mark.parametrize("workers", [1, 2])
def test_a_batch_of_a_hundred_million_seeds_starts_at_once_in_bounded_memory(
    tmp_path, capsys, workers
):
    out = tmp_path / "out"
    began = time.monotonic()
    tracemalloc.start()
    try:
        code = batch_main(["--task", "usb_c", "--seeds", "0:100000000", "--workers",
                           str(workers), "--out", str(out),
                           "--trial-function", f"{TRIALS}:interrupted_at_seed_3"])  # fmt: skip
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert time.monotonic() - began < 20  # building every spec first took about a minute
    assert peak < 20e6
    assert code == 130
    assert "interrupted by SIGINT after" in capsys.readouterr().err
    summary = json.loads((out / SUMMARY_NAME).read_text())
    assert summary["requested"] == 100_000_000 and 1 <= summary["n"] < 10  # what finished first
