"""The scripted sim demo end to end (no view, as fast as the simulation goes): every
manoeuvre's tilt torque has the documented sign, the episode records it all; bad input."""

import pytest

from controller.episode import read_episode
from controller.view.live_stream import FoxgloveLiveStream
from evaluation.teleop import demo_cli
from evaluation.teleop.pad_script import load_pad_script
from evaluation.teleop.signs import manoeuvres, measured_signs


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    out = tmp_path_factory.mktemp("demo") / "out"
    assert demo_cli.main(["--no-view", "--fast", "--out", str(out)]) == 0
    return read_episode(out / "episode.mcap")


def test_each_manoeuvre_gives_the_documented_tilt_torque_sign(demo):
    script = manoeuvres(load_pad_script(demo_cli.DEFAULT_SCRIPT))
    assert [m.action for m in script].count("vy") == 4 and [m.action for m in script].count(
        "wz"
    ) == 4
    checks = measured_signs(demo, script)
    assert all(c.ok for c in checks), [(c.manoeuvre, c.change) for c in checks]
    translation = [abs(c.change) for c in checks if c.manoeuvre.action == "vy"]
    assert min(translation) > 2e-4  # above the tilt channel's noise floor (raw mm)


def test_the_episode_records_the_demo_grasp_teleop_and_the_deadman(demo):
    transitions = [(m.value["from"], m.value["to"], m.value["reason"])
                   for m in demo.messages("/machine/transition")]  # fmt: skip
    assert transitions == [
        ("grasp", "teleop", "grasped_and_zeroed"),
        ("teleop", "done", "hand_back"),
    ]
    teleop = [m.value for m in demo.messages("/teleop/input")]
    assert all(t["deadman"] for t in teleop)
    assert any(t["in_control_by"] == "operator" for t in teleop)
    assert demo.complete and demo.info["controller"] == "teleop"


def test_a_taken_foxglove_port_is_one_line_and_exit_2(tmp_path, capsys):
    taken = FoxgloveLiveStream(port=0)
    try:
        code = demo_cli.main(["--no-view", "--fast", "--foxglove", "--foxglove-port",
                              str(taken.port), "--out", str(tmp_path / "o")])  # fmt: skip
    finally:
        taken.close()
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and f"127.0.0.1:{taken.port}" in err


def test_a_bad_script_is_one_line_naming_the_event(tmp_path, capsys):
    script = tmp_path / "pad.yaml"
    script.write_text("events:\n  - {t_s: 1.0, axes: {vy: 2.0}}\n")
    code = demo_cli.main(
        ["--no-view", "--fast", "--script", str(script), "--out", str(tmp_path / "o")]
    )
    err = capsys.readouterr().err
    assert code == 2 and "events[0]" in err and "axes.vy" in err and err.count("\n") == 1
