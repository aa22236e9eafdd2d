"""The slip evaluation runs on the gel model and writes its report (quick mode).

Its precision and recall are measured numbers, not asserted here; what is asserted are the
properties the detector must have on any run: negatives never flag slip and the re-zero
policy never recommends a re-zero while the grasp is loaded.
"""

import math

import pytest

from evaluation.experiments import slip_cli
from evaluation.experiments.slip_eval import evaluate


def test_quick_evaluation_reports_and_keeps_the_hard_properties(tmp_path):
    out = tmp_path / "SLIP.md"
    args = ["--quick", "--grips", "10", "--objects", "plate", "--out", str(out)]
    assert slip_cli.main(args) == 0
    text = out.read_text()
    assert "| 10 | plate |" in text and "| all | all |" in text
    assert "| 10 | plate | shear +x |" in text and "| 10 | plate | tilt x |" in text

    report = evaluate(grips_n=(10.0,), objects=("square_peg",), quick=True)
    overall = report["overall"]
    assert overall["frames"] == sum(row["frames"] for row in report["sequences"])
    assert overall["negative_false_alarm_rate"] == 0.0
    assert overall["rezero_under_load_frames"] == 0
    assert 0.0 <= overall["incipient"]["precision"] <= 1.0
    assert not math.isnan(overall["gross"]["recall"])
    positive = next(row for row in report["sequences"] if row["positive"])
    assert "incipient_delay" in positive and "gross_delay" in positive


@pytest.mark.parametrize(
    "args,message",
    [
        (["--grips", "ten"], "--grips 'ten'"),
        (["--grips", "10,-1"], "must be > 0"),
        (["--objects", "plate,cube"], "unknown object 'cube'"),
    ],
)
def test_bad_arguments_exit_2_naming_the_input(args, message, capsys):
    with pytest.raises(SystemExit) as stop:
        slip_cli.main(args)
    assert stop.value.code == 2
    assert message in capsys.readouterr().err


@pytest.mark.parametrize(
    "args,message",
    [
        (["--method", "nope"], "unknown estimator configuration 'nope'"),
        (["--grips", "nan"], "--grips 'nan'"),
        (["--grips", "inf"], "--grips 'inf'"),
        (["--grips", "10,"], "--grips '10,'"),
        (["--noise-grey", "-5"], "--noise-grey"),
        (["--noise-grey", "nan"], "--noise-grey"),
        (["--seed", "-1"], "--seed"),
        (["--objects", "plate,plate"], "'plate' is given twice"),
    ],
)
def test_nonsense_arguments_exit_2_before_any_work(args, message, capsys, monkeypatch):
    monkeypatch.setattr(slip_cli, "evaluate", lambda *a: pytest.fail("work began"))
    with pytest.raises(SystemExit) as stop:
        slip_cli.main(args)
    assert stop.value.code == 2
    assert message in capsys.readouterr().err


@pytest.mark.parametrize("out", ["/dev/full", "."])
def test_an_unwritable_report_is_refused_before_any_work(out, capsys, monkeypatch):
    monkeypatch.setattr(slip_cli, "evaluate", lambda *a: pytest.fail("work began"))
    assert slip_cli.main(["--quick", "--out", out]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("eval_slip: error: --out") and "\n" not in err
