"""scripts/evaluate.py --quick end to end (slow: about a minute), and make_dataset's errors."""

import pytest

from evaluation.offline.make_dataset_cli import main as make_dataset_main
from evaluation.run import main as evaluate_main


@pytest.mark.slow
def test_quick_evaluation_writes_the_report_and_charts(tmp_path):
    docs = tmp_path / "docs"
    assert evaluate_main(["--quick", "--docs", str(docs), "--work", str(tmp_path / "w")]) == 0
    report = (docs / "EVALUATION.md").read_text()
    assert "## 2. Speed against accuracy" in report and "## 4. Slip detection" in report
    assert "| 10 (tuning) | all |" not in report and "| all | all |" in report  # one grip
    for chart in ("pareto.png", "calibration_gelsight_mini-plate.png"):
        assert (docs / "figures" / chart).stat().st_size > 10_000


@pytest.mark.parametrize(
    "estimator,message",
    [("nope", "unknown estimator configuration 'nope'"), ("markers", "has none")],
)
def test_evaluate_rejects_a_bad_estimator_before_any_work(tmp_path, capsys, estimator, message):
    with pytest.raises(SystemExit) as stop:
        evaluate_main(["--estimator", estimator, "--docs", str(tmp_path), "--work", str(tmp_path)])
    assert stop.value.code == 2 and message in capsys.readouterr().err
    assert not (tmp_path / "EVALUATION.md").exists()


def test_make_dataset_rejects_an_unknown_sensor(tmp_path, capsys):
    assert make_dataset_main([str(tmp_path / "d"), "--sensor", "nope"]) == 2
    assert "unknown sensor configuration" in capsys.readouterr().err


def test_every_sweep_level_builds_a_valid_setting():
    from evaluation.sweeps import CONDITIONS

    for condition in CONDITIONS:
        assert condition.nominal in condition.levels, condition.name
        for level in condition.levels:
            condition.setting(level)  # raises ValueError naming the bad key
