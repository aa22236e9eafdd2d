"""The trial fingerprint tool: one digest of what a trial decided, wall time excluded; the
table written and compared; bad input is one line and exit 2."""

from __future__ import annotations

import csv
import dataclasses

import pytest

from controller.insertion import Phase
from controller.insertion.interface import Transition
from controller.run.result import TrialResult
from evaluation.bench import trial_fingerprints
from evaluation.bench.trial_fingerprints import COLUMNS, compare, main, outcome_digest, read_table

SHORT = ["--set", "touch_spiral.timeout_s=6.0"]  # the grasp, the approach, the search's start

RESULT = TrialResult(
    task="usb_c",
    controller="dipole",
    seed=3,
    success=True,
    status="inserted",
    failure_reason=None,
    time_to_insert_s=8.5,
    duration_s=9.0,
    max_wrist_force_n=4.0,
    force_limit_n=20.0,
    wall_time_s=2.0,
)
TRANSITIONS = (
    Transition(1.7, Phase.GRASP, Phase.APPROACH, "grasped"),
    Transition(3.24, Phase.APPROACH, Phase.SEARCH, "above_the_opening"),
)


def test_the_outcome_digest_ignores_wall_time_only():
    digest = outcome_digest(RESULT, TRANSITIONS)
    assert outcome_digest(dataclasses.replace(RESULT, wall_time_s=99.0), TRANSITIONS) == digest
    assert outcome_digest(dataclasses.replace(RESULT, duration_s=9.0 + 1e-12), TRANSITIONS) != (
        digest
    )
    later = (TRANSITIONS[0], dataclasses.replace(TRANSITIONS[1], t_s=3.25))
    assert outcome_digest(RESULT, later) != digest
    ruled = (TRANSITIONS[0], dataclasses.replace(TRANSITIONS[1], rule="probe"))
    assert outcome_digest(RESULT, ruled) != digest


@pytest.fixture(scope="module")
def table(tmp_path_factory):
    """A table of one short trial (seed 2), written by the tool."""
    path = tmp_path_factory.mktemp("fingerprints") / "before.csv"
    assert main(["--task", "usb_c", "--seeds", "2:3", *SHORT, "--out", str(path)]) == 0
    return path


def test_a_table_is_written_and_a_rerun_matches_it(table, capsys):
    with table.open(newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert [row["seed"] for row in rows] == ["2"] and list(rows[0]) == list(COLUMNS)
    assert rows[0]["transitions"].split(" ")[1] == "grasp>approach"
    assert len(rows[0]["outcome"]) == 16 and len(rows[0]["truth"]) == 16
    capsys.readouterr()
    assert main(["--task", "usb_c", "--seeds", "2:3", *SHORT, "--against", str(table)]) == 0
    out = capsys.readouterr().out
    assert out.startswith(",".join(COLUMNS)) and "1 of 1 seeds identical" in out


def test_a_changed_row_is_named_field_by_field(table):
    earlier = read_table(table)
    row = dict(next(iter(earlier.values())))
    changed = {**row, "outcome": "0" * 16, "duration_s": "1.0"}
    lines = compare([changed], earlier, table)
    assert lines[0].startswith(f"seed 2: outcome: {row['outcome']} -> 0000000000000000")
    assert f"duration_s: {row['duration_s']} -> 1.0" in lines[0]
    assert lines[-1].startswith("0 of 1 seeds identical")
    absent = {**row, "seed": "7"}
    assert compare([absent], earlier, table)[0] == f"seed 7: not in '{table}'"


def test_two_written_tables_are_compared_without_a_trial(table, tmp_path, capsys):
    text = table.read_text()
    changed = tmp_path / "after.csv"
    row = text.splitlines()[1].split(",")
    row[COLUMNS.index("outcome")] = "f" * 16
    changed.write_text("\n".join([text.splitlines()[0], ",".join(row)]) + "\n")
    assert main(["--compare", str(table), str(table)]) == 0
    assert capsys.readouterr().out == f"1 of 1 seeds identical to '{table}' (outcome and truth)\n"
    assert main(["--compare", str(table), str(changed)]) == 0
    out = capsys.readouterr().out
    assert out.startswith("seed 2: outcome: ") and "-> ffffffffffffffff" in out
    empty = tmp_path / "empty.csv"
    empty.write_text(text.splitlines()[0] + "\n")
    assert main(["--compare", str(table), str(empty)]) == 0
    assert "1 seeds of" in capsys.readouterr().out.splitlines()[-1]


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--task", "usb_c"], "the following arguments are required: --seeds"),
        (["--compare", "a.csv", "b.csv", "--task", "usb_c"], "runs no trial; drop --task"),
        (["--task", "usb_c", "--seeds", "3"], "argument --seeds: '3': expected A:B"),
        (["--task", "usb_c", "--seeds", "0:1", "--controller", "x"], "argument --controller"),
    ],
)
def test_a_bad_argument_is_a_usage_error_exit_2(args, message, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(args)
    assert exit_info.value.code == 2
    assert message in capsys.readouterr().err.strip().splitlines()[-1]


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--task", "nope", "--seeds", "0:1"], "unknown task configuration 'nope'"),
        (["--task", "usb_c", "--seeds", "0:1", "--against", "missing.csv"], "no such file"),
        (["--task", "usb_c", "--seeds", "0:1", "--out", "/dev/full"], "not a regular file"),
        (["--task", "usb_c", "--seeds", "0:1", "--out", "."], "is a folder"),
        (["--compare", "missing.csv", "missing.csv"], "--compare 'missing.csv': no such file"),
    ],
)
def test_a_bad_input_is_one_line_and_exit_2(args, message, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err.startswith("trial_fingerprints: error:") and message in err
    assert err.count("\n") == 1


def test_a_table_that_is_not_one_is_refused(tmp_path, capsys):
    other = tmp_path / "other.csv"
    other.write_text("seed,x\n1,2\n")
    assert main(["--task", "usb_c", "--seeds", "0:1", "--against", str(other)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("trial_fingerprints: error: --against") and "not a trial" in err
    assert "\n" not in err


def test_a_trial_that_raises_is_an_error_row(monkeypatch, tmp_path, capsys):
    def broken(task, controller, seed):
        raise RuntimeError(f"seed {seed} broke\non two lines")

    monkeypatch.setattr(trial_fingerprints, "run", broken)
    out = tmp_path / "errors.csv"
    assert main(["--task", "usb_a", "--seeds", "4:6", "--out", str(out)]) == 0
    with out.open(newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert [row["seed"] for row in rows] == ["4", "5"]
    assert rows[0]["status"] == "error" and rows[0]["truth"] == rows[0]["transitions"] == ""
    assert rows[1]["failure_reason"] == "error: RuntimeError: seed 5 broke on two lines"
    assert rows[0]["outcome"] != rows[1]["outcome"]
