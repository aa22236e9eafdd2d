"""The scripted sim demo end to end (no view, as fast as the simulation goes): every
manoeuvre's tilt torque has the documented sign, the episode records it all; bad input."""

import os
import signal

import pytest

from controller.cli import alignment_demo as demo_cli
from controller.cli.teleop_signs import manoeuvres, measured_signs
from controller.episode import read_episode
from controller.view.live_stream import FoxgloveLiveStream
from drivers.sim.twins.pad_script import load_pad_script
from tests.conftest import made_once


def _run_demo(out):
    assert demo_cli.main(["--no-view", "--fast", "--out", str(out)]) == 0


@pytest.fixture(scope="module")
def demo(run_root):
    """The scripted demo's episode, run once per test run (tests/conftest.py)."""
    return read_episode(made_once(run_root, "teleop_demo", _run_demo) / "episode.mcap")


def test_each_manoeuvre_gives_the_documented_tilt_torque_sign(demo):
    script = manoeuvres(load_pad_script(demo_cli.DEFAULT_SCRIPT))
    assert [m.action for m in script].count("vy") == 4 and [m.action for m in script].count(
        "wz"
    ) == 4
    checks = measured_signs(demo, script)
    assert all(c.ok for c in checks), [(c.manoeuvre, c.change) for c in checks]
    assert {c.unit for c in checks} == {"N*m"}  # calibrated, as docs/USER_GUIDE.md's table
    translation = [abs(c.change) for c in checks if c.manoeuvre.action == "vy"]
    assert min(translation) > 1e-2  # far above the changes too small to carry a sign


def test_the_sign_table_prints_each_change_with_its_unit(demo):
    table = demo_cli.sign_table(demo, manoeuvres(load_pad_script(demo_cli.DEFAULT_SCRIPT)))
    rows = table.splitlines()[1:]
    assert len(rows) == 8 and all(" N*m " in row and row.endswith("yes") for row in rows)


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
    assert "the port is taken" in err
    assert not (tmp_path / "o").exists()  # no empty folder that looks like a run's


def test_a_bad_script_is_one_line_naming_the_event(tmp_path, capsys):
    script = tmp_path / "pad.yaml"
    script.write_text("events:\n  - {t_s: 1.0, axes: {vy: 2.0}}\n")
    code = demo_cli.main(
        ["--no-view", "--fast", "--script", str(script), "--out", str(tmp_path / "o")]
    )
    err = capsys.readouterr().err
    assert code == 2 and "events[0]" in err and "axes.vy" in err and err.count("\n") == 1


@pytest.mark.parametrize(
    "events, said",
    [
        ("  - {t_s: 0.0, axes: {vx_typo: 0.5}}\n",
         "events[0] (t_s 0): key 'axes': unknown action 'vx_typo'"),
        ("  - {t_s: 0.0, buttons: {turbo: true}}\n",
         "events[0] (t_s 0): key 'buttons': unknown action 'turbo'"),
        ("  - {t_s: 3.0, axes: {vy: 0.5}}\n  - {t_s: 1.0, axes: {vy: 0.0}}\n",
         "events[1] (t_s 1): expected times in increasing order"),
    ],
)  # fmt: skip
def test_a_script_naming_an_unknown_action_or_out_of_order_is_one_line_and_no_out(
    events, said, tmp_path, capsys
):
    script = tmp_path / "pad.yaml"
    script.write_text("events:\n" + events)
    out = tmp_path / "o"
    code = demo_cli.main(["--no-view", "--fast", "--script", str(script), "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "Traceback" not in err, err
    assert err.startswith(f"teleop_demo: error: {script}: {said}"), err
    assert not out.exists()


class QuittingView:
    """Stands in for the view process: after ``after`` frames it sends 'rezero', then
    'quit', as the window's keys would (from the writer's thread, as the real watcher's)."""

    def __init__(self, mapping, out_dir, after=80):
        self.offered, self.dropped, self.after = 0, 0, after
        self.on_command = None
        self.mapping = mapping

    def start(self):
        pass

    def watch(self, on_command):
        self.on_command = on_command

    def offer(self, snapshot):
        self.offered += 1
        if self.offered == self.after:
            self.on_command("rezero")
        elif self.offered == self.after + 10:
            self.on_command("quit")

    def close(self):
        pass


def test_the_view_quitting_ends_the_demo_safely_with_exit_0(tmp_path, monkeypatch):
    from controller.view import window

    monkeypatch.setattr(window, "LiveView", QuittingView)
    out = tmp_path / "out"
    assert demo_cli.main(["--fast", "--out", str(out)]) == 0  # a view: QuittingView
    episode = read_episode(out / "episode.mcap")
    assert episode.outcome["reason"] == "signal"  # the loop's safe path, as Ctrl-C
    calls = [m.value["call"] for m in episode.messages("/tactile/push")]
    assert calls.count("rezero") == 2  # the grasp's, then the view's key
    ends = max(m.t_s for m in episode.messages("/loop/tick"))
    assert ends < 10.0  # long before the script's end (20.5 s)


def test_with_autonomy_the_pad_overrides_and_hand_back_resumes_from_the_contact_state(tmp_path):
    script = tmp_path / "pad.yaml"
    script.write_text(
        "events:\n"
        "  - {t_s: 0.0, buttons: {deadman: true}}\n"
        "  - {t_s: 6.0, axes: {vz: 0.5}}\n"  # up, off the board, during the search
        "  - {t_s: 6.5, axes: {vz: 0.0}}\n"
        "  - {t_s: 7.0, buttons: {hand_back: true}}\n"
    )
    out = tmp_path / "out"
    args = ["--autonomy", "--no-view", "--fast", "--script", str(script), "--duration", "10"]
    assert demo_cli.main([*args, "--out", str(out)]) == 0
    episode = read_episode(out / "episode.mcap")
    moves = [(m.value["from"], m.value["to"], m.value["reason"])
             for m in episode.messages("/machine/transition")]  # fmt: skip
    assert moves[:5] == [
        ("grasp", "approach", "grasped_and_zeroed"),
        ("approach", "search", "surface_contact"),
        ("search", "teleop", "operator_takeover"),
        ("teleop", "approach", "hand_back"),  # lifted clear of the board: no contact
        ("approach", "search", "surface_contact"),  # autonomy carries on
    ]
    assert episode.info["controller"] == "align"


@pytest.mark.parametrize("backend", ["sim", "real"])
@pytest.mark.parametrize("value", ["false", "true"])
def test_the_deadman_cannot_be_set_in_any_mode(tmp_path, capsys, backend, value):
    """The deadman is a safety rule, not a setting: ``--set`` naming it is refused in one
    line with exit 2, whatever its value and backend, and nothing is written."""
    out = tmp_path / "o"
    override = f"teleop.require_deadman={value}"
    code = demo_cli.main(["--no-view", "--backend", backend, "--set", override, "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1
    assert "teleop.require_deadman" in err and "safety rule" in err
    assert not out.exists()


def test_a_stick_without_the_deadman_never_moves_the_arm(tmp_path):
    """The issue's exact probe: a full stick from the start, the deadman never held."""
    script = tmp_path / "pad.yaml"
    script.write_text("events:\n  - {t_s: 0.0, axes: {vy: 1.0}}\n")
    out = tmp_path / "out"
    args = ["--no-view", "--fast", "--duration", "5", "--script", str(script)]
    assert demo_cli.main([*args, "--out", str(out)]) == 0
    episode = read_episode(out / "episode.mcap")
    teleop = [m.value for m in episode.messages("/teleop/input")]
    assert teleop and not any(t["in_control_by"] == "operator" for t in teleop)
    y = [m.value["tcp_xyz_m"][1] for m in episode.messages("/arm/status")]
    assert max(y) - min(y) < 1e-6


def test_duration_is_the_longest_the_demo_runs(tmp_path):
    out = tmp_path / "out"
    assert demo_cli.main(["--no-view", "--fast", "--duration", "5", "--out", str(out)]) == 0
    episode = read_episode(out / "episode.mcap")
    assert episode.outcome["reason"] == "max_duration"
    assert episode.counts["/loop/tick"] == 500  # 5 s at 100 Hz, not 10 s


def test_an_unplugged_pad_while_the_operator_drives_is_a_fault_and_exit_1(tmp_path, capsys):
    script = tmp_path / "pad.yaml"
    script.write_text(
        "events:\n"
        "  - {t_s: 0.0, buttons: {deadman: true}}\n"
        "  - {t_s: 3.0, axes: {vy: 0.5}}\n"
        "  - {t_s: 4.0, attached: false}\n"
    )
    out = tmp_path / "out"
    code = demo_cli.main(["--no-view", "--fast", "--script", str(script), "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 1 and err.count("\n") == 1, err
    assert err.startswith("teleop_demo: error: the run ended in a fault (safe stop done): gamepad")
    assert read_episode(out / "episode.mcap").outcome["reason"] == "fault"


def test_a_real_time_demo_prints_times_from_its_start_and_checks_its_signs(tmp_path, capsys):
    """Real time (the default): on the paced clock from 0, so the timeline and the sign
    checks read the run's own times, and a busy machine slows it without a fault."""
    out = tmp_path / "out"
    assert demo_cli.main(["--no-view", "--duration", "6", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    timeline = printed.splitlines()[1]
    assert timeline.endswith("grasp -> teleop (grasped_and_zeroed)")
    assert 0.0 < float(timeline.split()[0]) < 6.0
    assert "real time: the simulation" in printed
    first = next(line for line in printed.splitlines() if line.startswith("vy +1.00 (  4.0"))
    assert first.endswith("yes"), printed
    assert read_episode(out / "episode.mcap").time_range_s()[0] < 6.0


def test_a_real_run_without_devices_leaves_no_output_folder_and_no_sdk_banner(tmp_path, capsys):
    out = tmp_path / "o"
    assert demo_cli.main(["--backend", "real", "--no-view", "--out", str(out)]) == 1
    captured = capsys.readouterr()
    assert "SDK_VERSION" not in captured.out + captured.err
    assert captured.err.startswith("teleop_demo: error: ") and captured.err.count("\n") == 1
    assert not out.exists()


class InterruptingView(QuittingView):
    """Sends the process SIGINT after ``after`` frames, as Ctrl-C in the terminal would."""

    def offer(self, snapshot):
        self.offered += 1
        if self.offered == self.after:
            os.kill(os.getpid(), signal.SIGINT)


def test_ctrl_c_mid_run_is_a_safe_stop_one_line_and_130(tmp_path, monkeypatch, capsys):
    from controller.view import window

    monkeypatch.setattr(window, "LiveView", InterruptingView)
    out = tmp_path / "out"
    assert demo_cli.main(["--fast", "--out", str(out)]) == 130
    err = capsys.readouterr().err
    assert err.startswith("teleop_demo: interrupted by SIGINT (safe stop done); the episode")
    assert err.count("\n") == 1
    assert read_episode(out / "episode.mcap").outcome["reason"] == "signal"
