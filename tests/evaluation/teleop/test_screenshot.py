"""``teleop_screenshot.py``: the picture beside its episode, a time past the end refused, a
damaged episode drawn from what is readable."""

import pytest

from controller.cli import alignment_demo as demo_cli
from evaluation.teleop import screenshot


@pytest.fixture(scope="module")
def episode(tmp_path_factory):
    out = tmp_path_factory.mktemp("shot") / "run" / "demo"
    assert demo_cli.main(["--no-view", "--fast", "--duration", "5", "--out", str(out)]) == 0
    return out / "episode.mcap"


def _is_png(path):
    return path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_the_picture_may_go_beside_the_episode_or_in_any_folder_above_it(episode, capsys):
    for out in (episode.parent / "at3.png", episode.parent.parent.parent / "at3.png"):
        assert screenshot.main([str(episode), "--at", "3", "--out", str(out)]) == 0
        assert _is_png(out)
    capsys.readouterr()
    assert (
        screenshot.main([str(episode), "--at", "3", "--out", str(episode.with_suffix(".png"))]) == 0
    )
    assert screenshot.main([str(episode), "--at", "3", "--out", str(episode)]) == 2
    assert "expected a .png file" in capsys.readouterr().err  # and never the episode itself


def test_a_time_past_the_end_is_one_line_and_exit_2(episode, tmp_path, capsys):
    out = tmp_path / "late.png"
    assert screenshot.main([str(episode), "--at", "500", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("teleop_screenshot: error: --at 500: past the episode's end")
    assert err.count("\n") == 1 and not out.exists()


def test_a_damaged_episode_is_drawn_from_what_is_readable(episode, tmp_path, capsys):
    data = bytearray(episode.read_bytes())
    middle = len(data) // 2
    data[middle : middle + 100_000] = bytes(100_000)
    damaged = tmp_path / "damaged.mcap"
    damaged.write_bytes(bytes(data))
    out = tmp_path / "d.png"
    assert screenshot.main([str(damaged), "--at", "4.5", "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert err.startswith("teleop_screenshot: warning: ") and "is damaged" in err
    assert _is_png(out)
