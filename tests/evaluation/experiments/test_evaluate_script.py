"""python -m evaluation evaluate --quick end to end (slow: about a minute), and
make_dataset's errors."""

import pytest

from evaluation.experiments.run import main as evaluate_main
from evaluation.offline.make_dataset_cli import main as make_dataset_main


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
    from evaluation.experiments.sweeps import CONDITIONS

    for condition in CONDITIONS:
        assert condition.nominal in condition.levels, condition.name
        for level in condition.levels:
            condition.setting(level)  # raises ValueError naming the bad key


@pytest.mark.parametrize(
    "args,message",
    [
        (["--jobs", "0"], "--jobs"),
        (["--jobs", "-2"], "--jobs"),
        (["--jobs", "1.5"], "--jobs"),
        (["--frames-per-axis", "0"], "--frames-per-axis"),
    ],
)
def test_evaluate_refuses_nonsense_counts(tmp_path, capsys, args, message):
    with pytest.raises(SystemExit) as stop:
        evaluate_main([*args, "--docs", str(tmp_path), "--work", str(tmp_path)])
    assert stop.value.code == 2 and message in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    "make_args,message",
    [
        (lambda t: ["--docs", str(t / "file")], "is a file"),
        (lambda t: ["--work", str(t / "file")], "is a file"),
        (lambda t: ["--docs", "/proc/none"], "cannot write in"),
        (lambda t: ["--docs", str(t / "d"), "--work", str(t / "d" / "EVALUATION.md")], "is a"),
    ],
)
def test_evaluate_checks_its_outputs_before_any_work(
    tmp_path, capsys, monkeypatch, make_args, message
):
    import evaluation.experiments.run as run

    (tmp_path / "file").write_text("mine")
    (tmp_path / "d").mkdir()
    (tmp_path / "d" / "EVALUATION.md").write_text("previous")
    monkeypatch.setattr(run, "_run", lambda *a: pytest.fail("work began"))
    args = make_args(tmp_path)
    args += [] if "--docs" in args else ["--docs", str(tmp_path / "docs")]
    args += [] if "--work" in args else ["--work", str(tmp_path / "work")]
    assert evaluate_main(args) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("evaluate: error:") and message in err and "\n" not in err
    assert (tmp_path / "file").read_text() == "mine"
    assert (tmp_path / "d" / "EVALUATION.md").read_text() == "previous"


def test_an_interrupted_evaluation_keeps_the_previous_report(tmp_path, capsys, monkeypatch):
    import evaluation.experiments.run as run

    docs = tmp_path / "docs"
    (docs / "figures").mkdir(parents=True)
    (docs / "EVALUATION.md").write_text("previous report")
    (docs / "figures" / "pareto.png").write_bytes(b"previous chart")

    def interrupted(args, staging):
        (staging / "figures").mkdir()
        (staging / "figures" / "pareto.png").write_bytes(b"half a new chart")
        raise KeyboardInterrupt

    monkeypatch.setattr(run, "_run", interrupted)
    assert evaluate_main(["--docs", str(docs), "--work", str(tmp_path / "w")]) == 130
    assert "interrupted by SIGINT" in capsys.readouterr().err
    assert (docs / "EVALUATION.md").read_text() == "previous report"
    assert (docs / "figures" / "pareto.png").read_bytes() == b"previous chart"
    assert sorted(p.name for p in docs.iterdir()) == ["EVALUATION.md", "figures"]


def test_the_realistic_image_conditions_build_renderable_settings():
    """The tilt-motion, pushing and appearance sweeps: each level a distinct, valid setting
    whose appearance the renderer draws; speckle is one labelled level."""
    import numpy as np

    from evaluation.common.rendering import make_renderer
    from evaluation.common.sim_setup import jig_config
    from evaluation.experiments.sweeps import CONDITIONS, _program, peak_tilt_px

    by_name = {c.name: c for c in CONDITIONS}
    tilt = by_name["tilt motion (field amplitude)"]
    for px in tilt.levels:
        assert peak_tilt_px(tilt.setting(px).amplitude_nm) == pytest.approx(px, rel=1e-3)
    assert min(tilt.levels) == 0.2 and max(tilt.levels) == 3.0
    push = by_name["pushing (grip swing during tilt)"]
    assert max(push.levels) == 50
    program = _program(push.setting(50), jig_config(), np.random.default_rng(0))
    held = program.grip_n[program.t_s >= program.segments[0].t_start_s + 1.0]
    grip = jig_config().grip_force_n
    assert held.max() > 1.4 * grip and held.min() < 0.6 * grip
    texture = by_name["appearance: texture"]
    assert "speckle (old renderer)" in texture.labels
    assert sum(label.startswith("real: ") for label in texture.labels) == 5
    for condition in (by_name["appearance: lighting colour"], texture):
        for i, level in enumerate(condition.levels):
            setting = condition.setting(level)
            image = make_renderer(setting.sensor, setting.effects, 0, setting.appearance).render(
                np.zeros((30, 40, 2)), frame_index=0
            )
            assert image.shape == (240, 320, 3) and image.std() > 1.0, condition.level_label(i)


def test_breakdown_walks_away_from_nominal_both_ways():
    from evaluation.experiments.sweeps import CONDITIONS, LevelResult, breakdown

    tilt = next(c for c in CONDITIONS if c.name == "tilt motion (field amplitude)")
    r2 = {0.2: 0.5, 0.4: 0.8, 1.0: 0.99, 2.0: 0.99, 3.0: 0.95}  # fails at 0.4 first, below
    nrmse = {0.2: 0.1, 0.4: 0.1, 1.0: 0.1, 2.0: 0.1, 3.0: 0.25}  # doubles at 3 px, above
    results = [
        LevelResult(tilt.name, v, {"m": 1.0}, {"m": r2[v]}, {"m": nrmse[v]}, 10, {}, 10)
        for v in tilt.levels
    ]
    assert breakdown(tilt, results, "m") == "0.4 / 3"
    texture = next(c for c in CONDITIONS if c.name == "appearance: texture")
    results = [
        LevelResult(
            texture.name, v, {"m": 1.0}, {"m": 0.99 if v < 2 else 0.1}, {"m": 0.1}, 10, {}, 10
        )
        for v in texture.levels
    ]
    assert breakdown(texture, results, "m") == texture.labels[2]  # nominal first: one way
