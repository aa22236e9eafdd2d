"""The hole-find diagnosis: the true tip at each hole find and the attempt's end."""

import importlib
import math
import os
import signal
import threading

import numpy as np
import pytest

from controller.insertion import Phase, Transition
from controller.run.task import load_task
from evaluation.trials.hole_finds import (
    DROP_M,
    HoleFind,
    _attempt_outcome,
    resting_height_m,
    summary_lines,
    trial_hole_finds,
)
from evaluation.trials.hole_finds_cli import main


def test_the_resting_height_is_half_the_leading_face_times_the_sine_of_the_tilt():
    task = load_task("usb_c")
    assert resting_height_m(task) == pytest.approx(0.5 * 0.0024 * math.sin(0.2618))
    tilted_about_y = load_task("usb_c", ["machine.approach.tilt_axis=y"])
    assert resting_height_m(tilted_about_y) == pytest.approx(0.5 * 0.00825 * math.sin(0.2618))


def test_the_attempt_ends_at_the_first_release_back_off_or_failure():
    def tr(source, target, reason):
        return Transition(0.0, source, target, reason)

    aligned = tr(Phase.ALIGN, Phase.INSERT, "aligned")
    assert _attempt_outcome([aligned, tr(Phase.INSERT, Phase.RELEASE, "depth_reached")]) == (
        "inserted"
    )
    assert _attempt_outcome([aligned, tr(Phase.INSERT, Phase.BACKOFF, "not_engaged")]) == (
        "not_engaged"
    )
    assert _attempt_outcome([aligned, tr(Phase.INSERT, Phase.FAILED, "timeout")]) == "timeout"
    assert _attempt_outcome([aligned]) == "run ended"


def test_a_simulated_trial_ends_with_a_hole_find_in_the_opening_that_inserts(easy_task):
    task = easy_task("usb_c")  # the tool's diagnosis, not the machine's success
    success, finds = trial_hole_finds(task, 10)  # one find, in the opening
    assert success and finds
    assert finds[-1].in_opening and finds[-1].outcome == "inserted"
    resting = resting_height_m(task)
    for f in finds:
        assert f.rule in ("torque_catch", "load_drop", "torque_catch+load_drop")
        assert f.in_opening == (f.tip_o_m[2] <= resting - DROP_M)
        assert np.all(np.isfinite(f.tip_o_m))
        # every find of this trial was aligned; the wrist keeps the true tip within 5 mm
        assert all(0.0 <= e < 5e-3 for e in f.pivot_error_m)
    assert [f.t_s for f in finds] == sorted(f.t_s for f in finds)


def test_the_summary_counts_finds_by_place_and_end():
    finds = [
        HoleFind(0, 1.0, "load_drop", (0.0, 0.0, -1e-4), True, "inserted", (1e-3, 2e-3)),
        HoleFind(0, 2.0, "load_drop", (0.0, 0.0, 3e-4), False, "not_engaged", (2e-3, math.nan)),
        HoleFind(1, 1.0, "torque_catch", (0.0, 0.0, 3e-4), False, "not_engaged", (3e-3, 4e-3)),
    ]
    assert summary_lines(finds) == [
        "in the opening: 1 (inserted 1)",
        "on the surface: 2 (not_engaged 2)",
        "by load_drop: 2 (1 in the opening)",
        "by torque_catch: 1 (0 in the opening)",
        "pivot error at the finds (3): median 2.00 mm, 1.00-3.00 mm",
        "pivot error when ALIGN ended (2): median 3.00 mm, 2.00-4.00 mm",
    ]


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--task", "usb_c", "--seeds", "3:1"], "--seeds"),
        (["--task", "nope", "--seeds", "0:1"], "nope"),
        (
            ["--task", "usb_c", "--seeds", "0:1", "--set", "machine.search.pitch_m=-1"],
            "machine.search.pitch_m",
        ),
    ],
)
def test_bad_input_is_one_line_and_exit_2(argv, message, capsys):
    try:
        code = main(argv)
    except SystemExit as exc:
        code = exc.code
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert message in err[-1] and err[-1].startswith("hole_finds: error:")


def test_a_signal_that_stops_the_trial_stops_the_caller():
    """Ctrl-C during a trial: its loop stops safely, then the tool stops too (it does not
    go on to the next seed with a half-run trial). The simulator is imported first: a SIGINT
    that lands in MuJoCo's import is that import's ImportError, not a stop of the trial."""
    importlib.import_module("drivers.sim.scenes.insertion.physics")
    timer = threading.Timer(1.0, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            trial_hole_finds(load_task("usb_c"), 1)
    finally:
        timer.cancel()
