"""The press-and-roll measurement runs end to end: rendered frames, estimators, its table."""

from drivers.sim.render.image_effects import ImageEffects
from drivers.sim.scenes.press_roll import PressRollConfig
from evaluation.common.rendering import make_renderer
from evaluation.experiments import press_roll_eval

SHORT = PressRollConfig(open_frames=2, press_frames=8, roll_frames=8, press_rolled_frames=8)


def test_no_contact_frame_is_degenerate_or_silent_under_a_press():
    renderer = make_renderer("gelsight_mini", ImageEffects(noise_grey=2.0), seed=1)
    # The default's 4x4 dipole grid sees only positive divergence under this press: before
    # the continuous dipole it flagged degenerate with zero tilt in about 97% of the frames.
    (score,) = press_roll_eval.run("gelsight_mini", ["default"], renderer, SHORT)
    assert score.method == "default" and score.contact_frames == 8 + 2 * 8 + 8
    assert score.degenerate == 0.0 and score.zero_tilt == 0.0
    assert "| `default` | 32 | 0.0% | 0.0% |" in press_roll_eval.table([score])


def test_bad_method_is_a_one_line_error(capsys):
    try:
        press_roll_eval.main(["--methods", "no_such_estimator"])
    except SystemExit as exit_:
        assert exit_.code == 2
    else:
        raise AssertionError("expected exit code 2")
    err = capsys.readouterr().err
    assert err.startswith("eval_press_roll: error:") and err.count("\n") == 1
