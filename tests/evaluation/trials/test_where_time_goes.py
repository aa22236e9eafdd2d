"""python -m evaluation where_time_goes: where trials spend their time, rule by rule, and
where their failures end, from the records (synthetic ones here, with known times)."""

import json

import pytest

from evaluation.trials.where_time_goes import main, tick_seconds

PERIOD = 0.01


def _record(folder, seed, status, phases, tti=None, reason=None, transitions=()):
    """A record whose ticks run through ``phases`` [(phase, rule, seconds), ...] from t=1 s."""
    folder.mkdir(parents=True)
    trial = {
        "controller": "align",
        "seed": seed,
        "result": {"status": status, "time_to_insert_s": tti, "failure_reason": reason},
        "loop": {"first_tick_s": 1.0},
        "transitions": [
            {"t_s": 1.0, "from": src, "to": dst, "reason": why} for src, dst, why in transitions
        ],
    }
    (folder / "trial.json").write_text(json.dumps(trial))
    t, lines = 1.0, []
    for phase, rule, seconds in phases:
        for _ in range(round(seconds / PERIOD)):
            lines.append(json.dumps({"t_s": t, "phase": phase, "rule": rule}))
            t += PERIOD
    (folder / "ticks.jsonl").write_text("\n".join(lines) + "\n")


def _row(text, *cells):
    prefix = "|" + "|".join(f" {cell} " if cell else " " for cell in cells) + "|"
    return next(line for line in text.splitlines() if line.startswith(prefix))


def test_the_seconds_per_rule_are_the_ticks_up_to_the_time_to_insert(tmp_path, capsys):
    records = tmp_path / "batch" / "records"
    # 2 s searching, 1 s aligning, then 1 s inserting of which only 0.5 s count (tti 3.5 s)
    steps = [("search", "search.drag", 2.0), ("align", "align.turn", 1.0)]
    _record(records / "align-0", 0, "inserted", [*steps, ("insert", "insert.push", 1.0)], 3.5)
    # 4 s searching, 1 s aligning, 0.02 s of a rare rule (under --least), tti 5.02 s
    steps = [("search", "search.drag", 4.0), ("align", "align.turn", 1.0)]
    _record(records / "align-1", 1, "inserted", [*steps, ("align", "align.rare", 0.02)], 5.02)
    assert main([str(tmp_path / "batch")]) == 0
    text = capsys.readouterr().out
    assert "2 inserted, mean time to insert 4.26 s" in text
    assert _row(text, "search", "(all)", "3.00") and _row(text, "", "search.drag", "3.00")
    assert _row(text, "align", "(all)", "1.01")
    assert _row(text, "", "other", "0.01")  # the rare rule, 0.01 s a trial
    assert _row(text, "insert", "(all)", "0.25")  # half of one trial's second
    assert "failed" not in text


def test_failures_are_counted_by_the_phase_they_ended_in_and_whether_the_hole_was_found(
    tmp_path, capsys
):
    records = tmp_path / "records"
    never = [("grasp", "approach", "grasped_and_zeroed"), ("search", "failed", "timeout")]
    found = [("search", "align", "hole_found"), ("align", "failed", "timeout")]
    _record(records / "align-0", 0, "failed", [], reason="timeout", transitions=never)
    _record(records / "align-1", 1, "failed", [], reason="timeout", transitions=never)
    _record(records / "align-2", 2, "failed", [], reason="timeout", transitions=found)
    (records / ".align-3.partial").mkdir()  # an unfinished trial's record: left out
    assert main([str(tmp_path)]) == 0
    text = capsys.readouterr().out
    assert "3 failed" in text
    assert _row(text, "search", "timeout", "2", "2")
    assert _row(text, "align", "timeout", "1", "0")


def test_the_spirals_catch_and_fall_count_as_found(tmp_path, capsys):
    records = tmp_path / "records"
    never = [("grasp", "approach", "grasped"), ("search", "failed", "timeout")]
    caught = [("search", "insert", "caught"), ("insert", "search", "jammed"),
              ("search", "failed", "timeout")]  # fmt: skip
    fell = [("search", "insert", "fell_in"), ("insert", "failed", "timeout")]
    _record(records / "dipole-0", 0, "failed", [], reason="timeout", transitions=never)
    _record(records / "dipole-1", 1, "failed", [], reason="timeout", transitions=caught)
    _record(records / "dipole-2", 2, "failed", [], reason="timeout", transitions=fell)
    assert main([str(tmp_path)]) == 0
    text = capsys.readouterr().out
    assert _row(text, "search", "timeout", "2", "1")
    assert _row(text, "insert", "timeout", "1", "0")


def test_one_trials_record_is_read_alone(tmp_path, capsys):
    _record(tmp_path / "t", 7, "inserted", [("search", "search.drag", 1.0)], 1.0)
    assert main([str(tmp_path / "t")]) == 0
    assert "1 inserted, mean time to insert 1.00 s" in capsys.readouterr().out


def test_the_last_tick_lasts_one_period_and_a_tick_is_cut_at_the_time():
    ticks = [(0.0, "a", "x"), (0.01, "a", "x"), (0.02, "b", "y")]
    assert tick_seconds(ticks, 1.0) == pytest.approx({("a", "x"): 0.02, ("b", "y"): 0.01})
    assert tick_seconds(ticks, 0.015) == pytest.approx({("a", "x"): 0.015})


@pytest.mark.parametrize(
    ("make", "expected"),
    [
        (lambda p: None, "is not a folder"),
        (lambda p: p.mkdir(), "holds no trial.json"),
        (lambda p: (p.mkdir(), (p / "trial.json").write_bytes(b"\xff\xfe")), "not a readable"),
        (lambda p: (p.mkdir(), (p / "trial.json").write_text("{}")), "not a trial's result"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys, make, expected):
    make(tmp_path / "in")
    assert main([str(tmp_path / "in")]) == 2
    err = capsys.readouterr().err
    assert expected in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err


def test_a_broken_tick_log_names_its_file_and_line(tmp_path, capsys):
    _record(tmp_path / "t", 0, "inserted", [("search", "search.drag", 0.05)], 0.05)
    with (tmp_path / "t" / "ticks.jsonl").open("a") as ticks:
        ticks.write('{"t_s": 1.05, "phase": "search"\n')  # cut short, as by a crash
    assert main([str(tmp_path / "t")]) == 2
    err = capsys.readouterr().err
    assert "ticks.jsonl" in err and "line 6" in err and len(err.strip().splitlines()) == 1
