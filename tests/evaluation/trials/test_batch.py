"""Batches of trials: seeds, executors (local and Ray), summary, CSV, charts, CLI."""

import csv
import json
import math
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from controller.cli.support import ToolError
from controller.episode import read_episode
from controller.run.result import TrialResult
from core.config import CONFIG_ROOT
from evaluation.trials.batch import (
    CSV_COLUMNS,
    CSV_NAME,
    SUMMARY_NAME,
    Batch,
    read_batch,
    run_batches,
)
from evaluation.trials.batch_cli import TRIAL_FUNCTION
from evaluation.trials.batch_cli import main as batch_main
from evaluation.trials.charts import inserted_within, speed_success_chart, success_time_chart
from evaluation.trials.compare import main as compare_main
from evaluation.trials.executors import LocalExecutor, open_executor
from evaluation.trials.records import keep_record, unfinished_record
from evaluation.trials.spec import SeedSpecs, SpecError, TrialSpec, format_seeds, parse_seeds
from evaluation.trials.summary import quantile_over_all, summarize, wilson_ci
from tests.evaluation.trials.fake_trials import FORCE_LIMIT_N, fake_trial, slow_trial

ROOT = Path(__file__).resolve().parents[3]
TRIALS = fake_trial.__module__  # the trial functions by name (--trial-function)


def specs(seeds, controller="dipole", overrides=()):
    return [TrialSpec("usb_c", controller, s, tuple(overrides)) for s in seeds]


# -- seeds and specs ---------------------------------------------------------------------


def test_seeds_run_from_a_up_to_b_excluded():
    assert list(parse_seeds("3:7")) == [3, 4, 5, 6]
    assert list(parse_seeds(" 0 : 1 ")) == [0]
    assert format_seeds(parse_seeds("10:200")) == "10:200"


@pytest.mark.parametrize("text", ["5", "5:5", "7:3", "a:b", "-1:3", "1.5:3", "", "1:2:3", "0:1e3"])
def test_bad_seeds_are_one_line_errors(text):
    with pytest.raises(SpecError, match=r"seeds .*expected") as caught:
        parse_seeds(text)
    assert "\n" not in str(caught.value)


def test_spec_refuses_an_unknown_controller():
    with pytest.raises(
        SpecError,
        match=(
            "expected one of dipole, fingervision, zero_torque, torque_only, align, blind, oracle"
        ),
    ):
        TrialSpec("usb_c", "magic", 0)


# -- summary -------------------------------------------------------------------------------


def _wilson_by_formula(k, n, z=1.959963984540054):
    centre = (k + z * z / 2) / (n + z * z)
    half = z / (n + z * z) * math.sqrt(k * (n - k) / n + z * z / 4)
    return centre - half, centre + half


@pytest.mark.parametrize("k, n", [(0, 10), (8, 10), (10, 10), (196, 200), (1, 1)])
def test_wilson_interval_matches_the_formula(k, n):
    assert wilson_ci(k, n) == pytest.approx(_wilson_by_formula(k, n), abs=1e-9)


def test_wilson_interval_known_values():
    low, high = wilson_ci(8, 10)
    assert (round(low, 4), round(high, 4)) == (0.4902, 0.9433)
    assert wilson_ci(0, 0) is None


def _result(
    seed, success, time_s=None, force=1.0, reason=None, duration=10.0, wall=1.0, status=None
):
    status = status or ("inserted" if success else "failed")
    return TrialResult(
        "usb_c",
        "dipole",
        seed,
        success,
        status,
        reason,
        time_s,
        duration,
        force,
        FORCE_LIMIT_N,
        wall,
    )


def test_summary_values():
    results = [
        _result(0, True, 4.0),
        _result(1, True, 6.0, force=25.0),
        _result(2, True, 8.0),
        _result(3, False, reason="timeout"),
        _result(4, False, reason="timeout", force=21.0),
        _result(5, False, reason="slip", duration=30.0, wall=3.0),
    ]
    summary = summarize(results, task="usb_c", controller="dipole")
    assert summary["task"] == "usb_c" and summary["controller"] == "dipole"
    assert summary["n"] == 6 and summary["successes"] == 3
    assert summary["success_rate"] == 0.5
    assert summary["success_ci95"] == pytest.approx(_wilson_by_formula(3, 6))
    assert summary["median_time_s"] == 6.0
    assert summary["p90_time_s"] == pytest.approx(7.6)  # linear interpolation
    # over all six, the failures never: half failed, so the median lies between the 8 s
    # success and a failure, and so does the p90
    assert summary["median_time_all_s"] is None and summary["p90_time_all_s"] is None
    assert summary["max_wrist_force_n"] == 25.0
    assert summary["over_force_trials"] == 2
    assert summary["failures"] == {"slip": 1, "timeout": 2}
    assert summary["failed_seeds"] == [3, 4, 5]
    assert summary["sim_speed_x_realtime"] == pytest.approx(80.0 / 8.0)


def test_summary_counts_errors_by_status_not_by_reason():
    results = [
        _result(0, False, reason="error: a failure reason that happens to read so"),
        _result(1, False, reason="worker lost", duration=0.0, wall=5.0, status="error"),
    ]
    summary = summarize(results)
    assert summary["errors"] == 1
    assert summary["sim_duration_s"] == 10.0 and summary["wall_time_s"] == 1.0


def test_a_status_must_agree_with_success():
    with pytest.raises(ValueError, match="contradicts"):
        _result(0, True, 4.0, status="failed")
    with pytest.raises(ValueError, match="contradicts"):
        _result(0, False, status="inserted")
    with pytest.raises(ValueError, match="expected one of inserted, failed, error"):
        _result(0, False, status="crashed")


def test_summary_is_independent_of_arrival_order():
    results = [fake_trial(s) for s in specs([0, 1, 2, 3, 4, 6])]
    assert summarize(results) == summarize(results[::-1])


def test_summary_of_no_success_has_no_times():
    summary = summarize([_result(0, False, reason="timeout")])
    assert summary["median_time_s"] is None and summary["p90_time_s"] is None
    assert summary["median_time_all_s"] is None and summary["p90_time_all_s"] is None
    assert summary["success_rate"] == 0.0


def test_the_quantiles_over_every_trial_agree_with_numpy_where_no_failure_is_reached():
    times = [3.0, 9.0, 4.0, 7.5, 5.0, 6.0, 8.0, 4.5, 5.5]
    padded = sorted(times) + [np.inf]  # ten trials, one failure
    assert quantile_over_all(times, 10, 0.5) == pytest.approx(np.percentile(padded, 50))
    assert quantile_over_all(times, 10, 0.8) == pytest.approx(np.percentile(padded, 80))
    assert quantile_over_all(times, 10, 0.9) is None  # between 9 s and the failure
    assert quantile_over_all(times, 9, 0.9) == pytest.approx(np.percentile(times, 90))
    assert quantile_over_all([], 0, 0.5) is None


# -- batches -------------------------------------------------------------------------------


def _read_csv(path):
    with path.open(newline="") as handle:
        return list(csv.DictReader(handle))


def _run(tmp_path, executor, seeds=range(0, 12), function=fake_trial, name="batch"):
    batch = Batch(specs(seeds), tmp_path / name, {"task": "usb_c", "controller": "dipole"})
    stopped = run_batches(function, [batch], executor, progress=False)
    return batch, stopped


def test_batch_writes_summary_and_csv_and_turns_an_exception_into_an_error_trial(tmp_path):
    batch, stopped = _run(tmp_path, LocalExecutor(1))
    assert stopped is None
    summary = json.loads((tmp_path / "batch" / SUMMARY_NAME).read_text())
    assert summary["n"] == 12 and summary["requested"] == 12 and summary["complete"] is True
    assert summary["successes"] == 8  # 3, 7, 11 time out, 5 raises
    assert summary["failures"] == {"error: RuntimeError: boom second line": 1, "timeout": 3}
    assert summary["errors"] == 1
    assert summary["max_wrist_force_n"] == 21.0 and summary["over_force_trials"] == 1
    rows = _read_csv(tmp_path / "batch" / CSV_NAME)
    assert tuple(rows[0]) == CSV_COLUMNS
    assert [int(r["seed"]) for r in rows] == list(range(12))
    error = rows[5]
    assert error["success"] == "False" and error["failure_reason"].startswith("error: Runtime")
    assert error["status"] == "error"
    assert {r["status"] for i, r in enumerate(rows) if i != 5} == {"inserted", "failed"}
    assert error["time_to_insert_s"] == ""


def test_csv_streams_each_result_as_it_arrives(tmp_path):
    seen = []
    path = tmp_path / "batch" / CSV_NAME

    def check(result):
        seen.append(len(_read_csv(path)))

    batch = Batch(specs(range(4)), tmp_path / "batch")
    run_batches(fake_trial, [batch], LocalExecutor(1), progress=False, on_result=check)
    assert seen == [1, 2, 3, 4]  # on disk before the next trial starts


def test_the_progress_bar_shows_trials_done_success_so_far_and_time_left(tmp_path, capsys):
    batch = Batch(specs(range(4)), tmp_path / "batch")  # seed 3 times out
    run_batches(fake_trial, [batch], LocalExecutor(1), progress=True)
    bar = capsys.readouterr().err.replace("\r", "\n").splitlines()
    final = [line for line in bar if "4/4" in line][-1]
    assert "inserted 3/4 (75.0%)" in final
    assert re.search(r"\[\d\d:\d\d<\d\d:\d\d", final)  # time so far < time left


def test_a_folder_holding_a_batch_is_refused(tmp_path):
    from evaluation.trials.batch import check_batch_folder

    _run(tmp_path, LocalExecutor(1), seeds=range(2))
    with pytest.raises(ToolError, match="already holds a batch"):
        check_batch_folder(tmp_path / "batch")


def test_local_pool_gives_the_same_summary_as_in_process(tmp_path):
    serial, _ = _run(tmp_path, LocalExecutor(1), name="serial")
    pooled, _ = _run(tmp_path, LocalExecutor(2), name="pooled")
    assert pooled.summary == serial.summary
    assert sorted(r.seed for r in pooled.results) == list(range(12))


def test_interrupt_keeps_what_finished(tmp_path):
    batch = Batch(specs(range(3)), tmp_path / "batch")

    def interrupt(result):
        raise KeyboardInterrupt

    stopped = run_batches(
        slow_trial, [batch], LocalExecutor(2), progress=False, on_result=interrupt
    )
    assert stopped == "SIGINT"
    summary = json.loads((tmp_path / "batch" / SUMMARY_NAME).read_text())
    assert summary["complete"] is False and summary["requested"] == 3 and summary["n"] == 1
    assert len(_read_csv(tmp_path / "batch" / CSV_NAME)) == 1


def test_a_stopped_batch_resumes_where_it_stopped_and_ends_as_one_whole_run(tmp_path):
    whole, _ = _run(tmp_path, LocalExecutor(1), name="whole")
    batch = Batch(specs(range(12)), tmp_path / "batch", {"task": "usb_c", "controller": "dipole"})
    ran = []

    def stop_after_four(result):
        ran.append(result.seed)
        if len(ran) == 4:
            raise KeyboardInterrupt

    assert run_batches(fake_trial, [batch], LocalExecutor(1), False, stop_after_four) == "SIGINT"
    # a kill in mid-write leaves half a row: it is dropped, and its trial runs again
    with (tmp_path / "batch" / CSV_NAME).open("a") as handle:
        handle.write("usb_c,dipole,4,Tr")
    seen = []
    again = Batch(specs(range(12)), tmp_path / "batch", {"task": "usb_c", "controller": "dipole"})
    stopped = run_batches(
        fake_trial, [again], LocalExecutor(1), False, lambda r: seen.append(r.seed), resume=True
    )
    assert stopped is None and seen == list(range(4, 12))  # only the trials without a row
    rows = _read_csv(tmp_path / "batch" / CSV_NAME)
    assert [int(r["seed"]) for r in rows] == list(range(12))
    # read back as written (repr: the fake's NaN limit is not equal to itself)
    assert [repr(TrialResult.from_row(r)) for r in rows] == [repr(r) for r in again.results]
    summary = json.loads((tmp_path / "batch" / SUMMARY_NAME).read_text())
    assert summary["complete"] is True and summary["n"] == 12
    assert again.summary == whole.summary  # the same as the run that never stopped


def test_a_resume_with_other_arguments_or_without_a_batch_is_refused(tmp_path, capsys):
    assert run_cli(tmp_path, "--seeds", "0:4", "--set", "scene.friction=0.4") == 0
    for args, message in [
        (["--seeds", "0:4"], "was run with overrides ['scene.friction=0.4'], not []"),
        (["--seeds", "0:6", "--set", "scene.friction=0.4"], "was run with requested 4, not 6"),
    ]:
        before = (tmp_path / "out" / CSV_NAME).read_text()
        assert run_cli(tmp_path, *args, "--resume") == 2
        assert message in capsys.readouterr().err
        assert (tmp_path / "out" / CSV_NAME).read_text() == before  # untouched
    assert run_cli(tmp_path, "--seeds", "0:4", "--resume", out="nothing") == 2
    assert "not a folder holding a run to resume" in capsys.readouterr().err
    (tmp_path / "empty").mkdir()
    assert run_cli(tmp_path, "--seeds", "0:4", "--resume", out="empty") == 2
    assert "holds no batch to resume" in capsys.readouterr().err
    # the same arguments: nothing left to run, the summary written again
    assert run_cli(tmp_path, "--seeds", "0:4", "--set", "scene.friction=0.4", "--resume") == 0
    assert "3/4 succeeded" in capsys.readouterr().out


def test_a_resume_keeps_a_finished_trials_record_and_reruns_only_the_unfinished(tmp_path):
    records = tmp_path / "out" / "records"
    args = ["--seeds", "0:4", "--records", "--trial-function", f"{TRIALS}:recording_trial"]
    out = tmp_path / "out"
    assert batch_main(["--task", "usb_c", "--out", str(out), *args]) == 0
    # as if killed: seed 1's row written but its record not yet renamed; seeds 2 and 3 not
    # finished (their rows gone, seed 2's record half written)
    (records / "dipole-1").rename(records / ".dipole-1.partial")
    (records / "dipole-2").rename(records / ".dipole-2.partial")
    shutil.rmtree(records / "dipole-3")
    lines = (out / CSV_NAME).read_text().splitlines(keepends=True)
    (out / CSV_NAME).write_text("".join(lines[:3]))
    assert batch_main(["--task", "usb_c", "--out", str(out), *args, "--resume"]) == 0
    assert sorted(p.name for p in records.iterdir()) == [f"dipole-{i}" for i in range(4)]
    assert [int(r["seed"]) for r in _read_csv(out / CSV_NAME)] == [0, 1, 2, 3]
    # seed 1's record is the first run's, kept: the trial was not run again
    assert (records / "dipole-1" / "spec.txt").stat().st_mtime < (
        (records / "dipole-2" / "spec.txt").stat().st_mtime
    )


def test_a_refused_resume_changes_nothing_and_damage_is_named(tmp_path, capsys):
    out = tmp_path / "cmp"
    args = ["--task", "usb_c", "--seeds", "0:4", "--controllers", "dipole,blind"]
    args += ["--speeds", "0.01", "--out", str(out), "--trial-function", FAKE]
    assert compare_main(args) == 0
    dipole, blind = (out / "cells" / c / "0.01" for c in ("dipole", "blind"))
    (dipole / CSV_NAME).write_text((dipole / CSV_NAME).read_text()[:-30])  # a half row
    before = (dipole / CSV_NAME).read_text()
    plan = json.loads((blind / "batch.json").read_text())
    (blind / "batch.json").write_text(json.dumps({**plan, "requested": 9}))
    assert compare_main([*args, "--resume"]) == 2
    assert "was run with requested 9, not 4" in capsys.readouterr().err
    assert (dipole / CSV_NAME).read_text() == before  # the first cell untouched
    (blind / "batch.json").write_text(json.dumps(plan))
    rows = (blind / CSV_NAME).read_text().splitlines(keepends=True)
    (blind / CSV_NAME).write_text("".join([rows[0], rows[1], rows[1], *rows[2:]]))
    assert compare_main([*args, "--resume"]) == 2
    assert "seed 0 has two rows" in capsys.readouterr().err
    (blind / CSV_NAME).write_text("".join([rows[0], rows[1][:40] + "\n", *rows[2:]]))
    assert compare_main([*args, "--resume"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "row 1 is damaged" in err
    (blind / CSV_NAME).unlink()  # stopped before its first row: the cell runs whole
    assert compare_main([*args, "--resume"]) == 0
    assert len(_read_csv(blind / CSV_NAME)) == 4 and len(_read_csv(dipole / CSV_NAME)) == 4


# -- Ray -------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def ray_available():
    return pytest.importorskip("ray")


def test_ray_gives_the_same_summary_as_local(tmp_path, ray_available):
    local, _ = _run(tmp_path, LocalExecutor(1), name="local")
    began = time.perf_counter()
    remote, stopped = _run(tmp_path, open_executor("ray", workers=2), name="ray")
    print(f"ray batch took {time.perf_counter() - began:.1f} s")
    assert stopped is None
    assert remote.summary == local.summary
    assert json.loads((tmp_path / "ray" / SUMMARY_NAME).read_text()) == json.loads(
        (tmp_path / "local" / SUMMARY_NAME).read_text()
    )


# -- command line --------------------------------------------------------------------------

FAKE = f"{TRIALS}:fake_trial"


def run_cli(tmp_path, *args, out="out"):
    return batch_main(
        ["--task", "usb_c", "--out", str(tmp_path / out), "--trial-function", FAKE, *args]
    )


def test_cli_runs_a_batch(tmp_path, capsys):
    assert run_cli(tmp_path, "--seeds", "0:8", "--set", "scene.friction=0.4") == 0
    summary = json.loads((tmp_path / "out" / SUMMARY_NAME).read_text())
    assert summary["seeds"] == "0:8" and summary["n"] == 8 and summary["successes"] == 5
    assert summary["overrides"] == ["scene.friction=0.4"]
    assert summary["executor"] == "local" and summary["workers"] == 1
    assert summary["controller"] == "dipole" and summary["task"] == "usb_c"
    assert "5/8 succeeded" in capsys.readouterr().out


@pytest.mark.parametrize(
    "args, message",
    [
        (["--seeds", "5:2"], "argument --seeds"),
        (["--seeds", "0:2", "--workers", "0"], "argument --workers"),
        (["--seeds", "0:2", "--controller", "magic"], "argument --controller"),
        (["--seeds", "0:2", "--executor", "dask"], "argument --executor"),
        (["--seeds", "0:2", "--set", "scene.friction"], "argument --set"),
        (["--seeds", "0:2", "--ray-address", "auto"], "only with --executor ray"),
    ],
)
def test_bad_cli_arguments_exit_2(tmp_path, capsys, args, message):
    with pytest.raises(SystemExit) as caught:
        run_cli(tmp_path, *args)
    assert caught.value.code == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err


@pytest.mark.parametrize(
    "args, message",
    [
        (["--seeds", "0:2", "--set", "scene.frction=1"], "override 'scene.frction=1'"),
        (["--seeds", "0:2", "--trial-function", "nowhere.at_all:run"], "cannot be imported"),
    ],
)
def test_bad_inputs_found_before_any_trial_exit_2(tmp_path, capsys, args, message):
    assert run_cli(tmp_path, *args) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err and err.startswith("run_trials: error:")
    assert not (tmp_path / "out" / CSV_NAME).exists()


def test_cli_refuses_an_unknown_task_and_a_folder_holding_a_batch(tmp_path, capsys):
    assert (
        batch_main(
            [
                "--task",
                "usb_x",
                "--seeds",
                "0:2",
                "--out",
                str(tmp_path / "a"),
                "--trial-function",
                FAKE,
            ]
        )
        == 2
    )
    assert "unknown task configuration 'usb_x'" in capsys.readouterr().err
    assert run_cli(tmp_path, "--seeds", "0:2") == 0
    assert run_cli(tmp_path, "--seeds", "0:2") == 2
    assert "already holds a batch" in capsys.readouterr().err


def test_records_give_each_trial_its_own_folder(tmp_path):
    assert (
        run_cli(
            tmp_path,
            "--seeds",
            "0:2",
            "--controller",
            "blind",
            "--records",
            "--trial-function",
            f"{TRIALS}:recording_trial",
        )
        == 0
    )
    text = (tmp_path / "out" / "records" / "blind-1" / "spec.txt").read_text()
    assert "seed=1" in text and "controller='blind'" in text


@pytest.mark.parametrize(
    "content", [{"usb_c.yaml": (CONFIG_ROOT / "tasks" / "usb_c.yaml").read_text()},
                {"trial.json": "{}", "summary.png": "inserted"}, {".hidden": ""}],
    ids=["a task file", "a trial's record", "a hidden file"],
)  # fmt: skip
def test_an_out_that_is_not_empty_and_holds_no_batch_is_refused(tmp_path, capsys, content):
    out = tmp_path / "out"
    out.mkdir()
    for name, text in content.items():
        (out / name).write_text(text)
    assert run_cli(tmp_path, "--seeds", "0:2", "--records") == 2
    assert capsys.readouterr().err == (
        f"run_trials: error: --out '{out}' is not empty and holds no batch; "
        "expected a new or empty folder\n"
    )
    assert sorted(p.name for p in out.iterdir()) == sorted(content)


def test_an_empty_out_is_accepted(tmp_path):
    (tmp_path / "out").mkdir()
    assert run_cli(tmp_path, "--seeds", "0:2") == 0


def test_a_record_is_never_written_over(tmp_path):
    unfinished = unfinished_record(tmp_path, "dipole", 3)
    unfinished.mkdir()
    (tmp_path / "dipole-3").mkdir()
    with pytest.raises(ToolError, match=r"dipole-3' exists already; a trial's record is never"):
        keep_record(unfinished)
    assert unfinished.is_dir() and not any((tmp_path / "dipole-3").iterdir())


def test_a_real_batch_keeps_each_trials_record_with_its_chart(tmp_path):
    out = tmp_path / "out"
    code = batch_main(["--task", "usb_c", "--seeds", "4:5", "--records", "--out", str(out),
                       "--set", "touch_spiral.timeout_s=6.0"])  # fmt: skip
    assert code == 0
    assert [p.name for p in (out / "records").iterdir()] == ["dipole-4"]
    record = out / "records" / "dipole-4"
    assert json.loads((record / "trial.json").read_text())["seed"] == 4
    assert (record / "summary.png").stat().st_size > 10000
    assert not (record / "episode.mcap").exists()  # episodes are opt-in


def test_a_batch_with_episodes_keeps_each_trials_episode_in_its_record(tmp_path):
    out = tmp_path / "out"
    code = batch_main(["--task", "usb_c", "--seeds", "4:5", "--episodes", "--out", str(out),
                       "--set", "touch_spiral.timeout_s=3.0"])  # fmt: skip
    assert code == 0
    episode = read_episode(out / "records" / "dipole-4" / "episode.mcap")
    assert episode.complete and episode.info["seed"] == "4"
    assert json.loads(episode.outcome["result"])["seed"] == 4
    assert episode.counts["/loop/tick"] > 100 and episode.counts["/sim/truth"] > 100


def test_an_episode_needs_a_record_folder():
    with pytest.raises(SpecError, match="episode: a trial writes its episode into its out_dir"):
        TrialSpec("usb_c", "dipole", 0, episode=True)
    with pytest.raises(SpecError, match="episodes: each trial's episode goes into its record"):
        SeedSpecs("usb_c", "dipole", range(2), episodes=True)


def test_default_trial_function_is_the_real_runner():
    assert TRIAL_FUNCTION == "evaluation.trials.trial:run_trial"


def test_ray_missing_is_a_one_line_error(monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)
    monkeypatch.delitem(sys.modules, "evaluation.trials.ray_executor", raising=False)
    with pytest.raises(ToolError, match=r"^the Ray executor needs Ray.*tactile-insertion\[ray\]"):
        open_executor("ray", workers=1)


# -- comparison and charts ---------------------------------------------------------------------


def test_compare_runs_the_grid_and_writes_charts_and_table(tmp_path, capsys):
    out = tmp_path / "cmp"
    code = compare_main(
        [
            "--task",
            "usb_c",
            "--seeds",
            "0:6",
            "--controllers",
            "dipole,align,blind,oracle",
            "--speeds",
            "0.01,0.02",
            "--out",
            str(out),
            "--trial-function",
            FAKE,
        ]
    )
    assert code == 0
    for name in ("speed_success.png", "time_to_insert_0.01.png", "time_to_insert_0.02.png"):
        assert (out / name).stat().st_size > 1000
    table = (out / "comparison.md").read_text()
    results, targets = table.split("### Targets at", 1)
    assert results.count("\n| ") == 1 + 8  # header and one row per cell
    # the product's targets judged at each speed, a controller not in the grid not judged
    assert targets.count("### Targets at") == 1  # the second speed's
    assert "machine.insert.speed_m_s=0.01\n" in targets and "=0.02\n" in targets
    assert "| `zero_torque` falls short of `dipole`, the intervals apart | – | not run |" in targets
    assert "oracle (true wrench + sensor noise)" in table and "![success against" in table
    # the in-hand estimate: table rows and a histogram per align and dipole cell (each scored
    # in its own plane, the other plane not estimated), none for the others
    assert sorted(p.name for p in out.glob("grasp_errors_*.png")) == [
        "grasp_errors_align_0.01.png",
        "grasp_errors_align_0.02.png",
        "grasp_errors_dipole_0.01.png",
        "grasp_errors_dipole_0.02.png",
    ]
    # the raising seed 5 has no estimate; dipole's seed 2 none either
    width, thickness = "tilt about T y (width plane), deg", "tilt about T x (thickness plane), deg"
    assert table.count(f"| align | 0.01 | {width} | 5/6 |") == 1
    assert table.count("| align | 0.01 | tip offset along T x, mm | 5/6 |") == 1
    assert table.count(f"| align | 0.01 | {thickness} | not estimated |") == 1
    assert table.count(f"| dipole | 0.01 | {thickness} | 4/6 |") == 1
    assert table.count("| dipole | 0.01 | tip offset along T y, mm | 4/6 |") == 1
    assert table.count(f"| dipole | 0.01 | {width} | not estimated |") == 1
    assert "| blind |" not in table.split("The plug in the hand")[1]
    dipole = json.loads((out / "cells" / "dipole" / "0.01" / SUMMARY_NAME).read_text())
    errors = dipole["grasp_estimate"]["errors"]
    assert set(errors) == {"thickness_tilt_deg", "tip_y_mm"}
    assert errors["tip_y_mm"] == {
        "n": 4,
        "median": pytest.approx(0.2),
        "p95": pytest.approx(0.385),
        "max": pytest.approx(0.4),
    }  # seeds 0, 1, 3, 4: 0, 0.1, 0.3, 0.4 mm
    summary = json.loads((out / "cells" / "blind" / "0.02" / SUMMARY_NAME).read_text())
    assert summary["overrides"] == ["machine.insert.speed_m_s=0.02"]
    assert summary["controller"] == "blind" and summary["n"] == 6
    every = json.loads((out / "comparison.json").read_text())
    assert len(every) == 8
    # the fake trial is slower at the lower speed: the histogram's data differ by speed
    slow = json.loads((out / "cells" / "dipole" / "0.01" / SUMMARY_NAME).read_text())
    assert slow["median_time_s"] > summary["median_time_s"]


def test_compare_resumes_each_cell_and_rewrites_the_same_comparison(tmp_path, capsys):
    out = tmp_path / "cmp"
    args = ["--task", "usb_c", "--seeds", "0:6", "--controllers", "dipole,blind"]
    args += ["--speeds", "0.01", "--out", str(out), "--trial-function", FAKE]
    assert compare_main(args) == 0
    table = (out / "comparison.md").read_text()
    # one cell lost its last two rows (stopped there): the resume runs just those
    blind = out / "cells" / "blind" / "0.01" / CSV_NAME
    lines = blind.read_text().splitlines(keepends=True)
    blind.write_text("".join(lines[:-2]))
    assert compare_main([*args, "--resume"]) == 0
    assert (out / "comparison.md").read_text() == table
    assert len(_read_csv(blind)) == 6
    assert compare_main([*args[:3], "0:7", *args[4:], "--resume"]) == 2
    assert "was run with requested 6, not 7" in capsys.readouterr().err
    assert compare_main(args) == 2  # without --resume: refused, named
    assert "already holds a comparison (cells/)" in capsys.readouterr().err


def test_compare_refuses_the_speed_key_in_set(tmp_path, capsys):
    with pytest.raises(SystemExit) as caught:
        compare_main(
            [
                "--task",
                "usb_c",
                "--seeds",
                "0:2",
                "--out",
                str(tmp_path),
                "--set",
                "machine.insert.speed_m_s=1",
                "--trial-function",
                FAKE,
            ]
        )
    assert caught.value.code == 2
    assert "is the speed key" in capsys.readouterr().err


def test_charts_with_an_empty_controller(tmp_path):
    summary = summarize([_result(0, True, 4.0), _result(1, False, reason="timeout")])
    speed_success_chart(
        {"dipole": [(0.01, summary)], "blind": []}, tmp_path / "a.png", "speed", "t"
    )
    success_time_chart(
        {"dipole": [4.0, 5.0], "blind": []}, {"dipole": 4, "blind": 4}, tmp_path / "b.png", "t"
    )
    assert (tmp_path / "a.png").stat().st_size > 1000
    assert (tmp_path / "b.png").stat().st_size > 1000


def test_success_against_time_counts_every_trial_and_ends_at_the_success_rate():
    steps, shares = inserted_within([9.0, 3.0, 5.0], 4, 20.0)
    assert steps.tolist() == [0.0, 3.0, 5.0, 9.0, 20.0]
    assert shares.tolist() == [0.0, 25.0, 50.0, 75.0, 75.0]  # 3 of 4 inserted: it ends at 75 %
    steps, shares = inserted_within([], 5, 20.0)
    assert shares.tolist() == [0.0, 0.0]


def test_an_unreachable_ray_address_is_a_quick_one_line_error(ray_available):
    from evaluation.trials.ray_executor import check_reachable

    with pytest.raises(ToolError, match=r"--ray-address 127.0.0.1:1: cannot connect"):
        check_reachable("127.0.0.1:1")
    with pytest.raises(ToolError, match=r"expected auto, HOST:PORT"):
        check_reachable("somewhere")


def test_sigterm_stops_the_batch_and_keeps_what_finished(tmp_path):
    out = tmp_path / "out"
    code = "import sys; from evaluation.trials.batch_cli import main; sys.exit(main(sys.argv[1:]))"
    process = subprocess.Popen(
        [
            sys.executable,
            "-c",
            code,
            "--task",
            "usb_c",
            "--seeds",
            "0:3",
            "--workers",
            "2",
            "--out",
            str(out),
            "--trial-function",
            f"{TRIALS}:slow_trial",
        ],
        cwd=ROOT,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and not (
        (out / CSV_NAME).exists() and len(_read_csv(out / CSV_NAME)) == 1
    ):
        time.sleep(0.1)
    process.send_signal(signal.SIGTERM)
    _, err = process.communicate(timeout=30)
    assert process.returncode == 143, err
    assert "interrupted by SIGTERM after 1 of 3 trials" in err
    summary = json.loads((out / SUMMARY_NAME).read_text())
    assert summary["complete"] is False and summary["n"] == 1 and summary["requested"] == 3


def test_a_table_from_before_a_pose_column_is_read_but_not_resumed(tmp_path, capsys):
    out = tmp_path / "batch"
    args = ["--task", "usb_c", "--seeds", "0:3", "--controller", "blind", "--out", str(out)]
    assert batch_main([*args, "--trial-function", FAKE]) == 0
    rows = _read_csv(out / CSV_NAME)
    older = [c for c in CSV_COLUMNS if c != "tip_y_est_m"]
    with open(out / CSV_NAME, "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=older, extrasaction="ignore")
        writer.writeheader()
        writer.writerows(rows)
    plan, results = read_batch(out)
    assert [r.seed for r in results] == [0, 1, 2]
    assert all(math.isnan(r.tip_y_est_m) for r in results)
    assert batch_main([*args, "--trial-function", FAKE, "--resume"]) == 2
    assert "its columns differ" in capsys.readouterr().err
    shuffled = [older[1], older[0], *older[2:]]  # not this version's order: not a table of it
    with open(out / CSV_NAME, "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=shuffled, extrasaction="ignore")
        writer.writeheader()
        writer.writerows(rows)
    with pytest.raises(ToolError, match="its columns differ"):
        read_batch(out)
