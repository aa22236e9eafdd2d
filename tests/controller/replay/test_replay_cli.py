"""The replay tools on a real recorded episode: summary, plot, reestimate, and the errors
(missing, foreign and truncated files: one line, exit code 2)."""

from __future__ import annotations

import csv
import math
import shutil
import time

import numpy as np
import pytest
from mcap.reader import make_reader

from controller.cli.replay import main
from controller.episode import read_episode
from controller.replay import episode_streams, reestimation
from controller.tactile import estimator_for_sensor
from controller.tactile.wrench import VALUE_FIELDS


def one_error_line(capsys) -> str:
    err = capsys.readouterr().err.strip()
    assert err.startswith("replay: error: ") and "\n" not in err and "Traceback" not in err
    return err


def test_summary_names_every_topic_with_its_count_and_the_run(episode_path, capsys):
    episode = read_episode(episode_path)
    assert main(["summary", str(episode_path)]) == 0
    out = capsys.readouterr().out
    assert "file: complete" in out and "task: usb_c" in out and "controller: dipole" in out
    for topic, count in episode.counts.items():
        assert any(line.split()[:2] == [topic, str(count)] for line in out.splitlines())
    rates = {line.split()[0]: float(line.split()[-2]) for line in out.splitlines() if "Hz" in line
             and line.split()[-2] != "-"}  # fmt: skip
    # the camera's 25 Hz with its capture jitter; the loop's 100 Hz on the simulated clock
    assert rates["/tactile/image"] == pytest.approx(25.0, rel=0.01)
    assert rates["/loop/tick"] == pytest.approx(100.0, rel=1e-3)
    changes = episode_streams.transitions(episode)
    assert f"transitions: {len(changes)}" in out and len(changes) >= 5
    lines = out.splitlines()
    assert any(line.endswith("grasp -> approach: grasped") for line in lines)
    assert any(line.endswith("search -> insert: caught") for line in lines)
    bottomed = next(c for c in changes if c.reason == "bottomed")
    assert bottomed.rule and f"insert -> release: bottomed ({bottomed.rule})" in out
    assert "outcome: done" in out and "dropped: 0 records" in out


def test_plot_draws_the_chart_and_never_writes_over_the_episode(episode_path, tmp_path, capsys):
    out = tmp_path / "chart.png"
    assert main(["plot", str(episode_path), "--out", str(out)]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and out.stat().st_size > 20_000
    before = episode_path.read_bytes()
    capsys.readouterr()
    assert main(["plot", str(episode_path), "--out", str(episode_path)]) == 2
    assert "expected a .png file" in one_error_line(capsys)
    link = tmp_path / "link.png"
    link.symlink_to(episode_path)
    assert main(["plot", str(episode_path), "--out", str(link)]) == 2
    assert "never writes over its inputs" in one_error_line(capsys)
    assert main(["plot", str(episode_path), "--out", str(tmp_path / "chart.txt")]) == 2
    assert "expected a .png file" in one_error_line(capsys)
    assert not (tmp_path / "chart.txt").exists()
    assert episode_path.read_bytes() == before


def test_reestimate_with_the_runs_configuration_reproduces_the_logged_estimates_exactly(
    episode_path,
):
    episode = read_episode(episode_path)
    run = reestimation.run_estimator(episode)
    assert (run.sensor, run.estimator) == ("gelsight_mini", "default")
    assert run.calibration is not None  # the task's, attached to the episode
    new = reestimation.reestimate(
        episode, estimator_for_sensor(run.sensor, run.estimator, run.calibration),
        time.perf_counter,
    )  # fmt: skip
    logged = episode_streams.estimates(episode)
    np.testing.assert_array_equal(new.push_index, logged.push_index)
    np.testing.assert_array_equal(new.t_s, logged.t_s)
    for column, name in enumerate(VALUE_FIELDS):
        # NaN (logged as null) equals NaN; every other value bit for bit
        np.testing.assert_array_equal(new.column(name), logged.values[:, column])
    assert np.array_equal(np.array([e.contact for e in new.estimates]), logged.contact)
    assert logged.contact.sum() > 30  # the comparison covers frames in contact
    assert np.abs(logged.column("tau_z")).max() > 1e-3  # and non-zero torques


def test_reestimate_reports_and_writes_the_csv(episode_path, tmp_path, capsys):
    out = tmp_path / "new.csv"
    assert main(["reestimate", str(episode_path), "--method", "default", "--out", str(out)]) == 0
    report = capsys.readouterr().out
    frames = read_episode(episode_path).counts["/tactile/image"]
    for axis in ("tau_x", "tau_y", "tau_z"):
        assert f"{axis}: R^2 1.000000, RMSE 0 (N*m) over {frames} frames, {frames} of " \
               f"{frames} frames identical" in report  # fmt: skip
    with out.open() as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == frames and rows[0]["frame"] == "0"
    assert float(rows[-1]["time_s"]) == pytest.approx(
        episode_streams.estimates(read_episode(episode_path)).t_s[-1], abs=1e-6
    )


def test_another_configuration_is_scored_against_the_logged_estimates(episode_path, capsys):
    assert main(["reestimate", str(episode_path), "--method", "dis_half"]) == 0
    report = capsys.readouterr().out
    truth, logged = report.split("against the logged estimates")
    assert "against the truth (/sim/truth" in truth
    lines = [line for line in truth.splitlines() if line.strip().startswith("tau_")]
    assert len(lines) == 3 and all("N*m" in line for line in lines)
    r2 = [float(line.split("R^2 ")[1].split(",")[0]) for line in lines]
    assert all(math.isfinite(v) for v in r2)
    # the run's calibration was fitted for 'default': another configuration stays raw, and
    # raw values are not compared with the calibrated ones logged
    assert "raw: the run's calibration is for another configuration" in report
    assert logged.startswith(": not compared (they are calibrated, N*m; these are raw)")


def test_reestimate_refuses_an_unknown_configuration(episode_path, capsys):
    assert main(["reestimate", str(episode_path), "--method", "no_such_method"]) == 2
    assert "no_such_method" in one_error_line(capsys)


# -- errors: a missing, a foreign and a truncated file ---------------------------------------


@pytest.mark.parametrize(
    "command", [["summary"], ["plot", "--out", "x.png"], ["reestimate", "--method", "default"]]
)
def test_a_missing_file_is_one_line_and_exit_2(command, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    missing = tmp_path / "missing.mcap"
    assert main([command[0], str(missing), *command[1:]]) == 2
    err = one_error_line(capsys)
    assert str(missing) in err and "No such file" in err


@pytest.mark.parametrize("content", [b"", b"ticks,phase\n1,grasp\n", b"\x89PNG\r\n\x1a\n" * 40])
def test_a_foreign_file_is_one_line_and_exit_2(content, tmp_path, capsys):
    foreign = tmp_path / "foreign.mcap"
    foreign.write_bytes(content)
    assert main(["summary", str(foreign)]) == 2
    err = one_error_line(capsys)
    assert str(foreign) in err and "not an MCAP file" in err


def test_a_folder_is_one_line_and_exit_2(tmp_path, capsys):
    assert main(["summary", str(tmp_path)]) == 2
    assert "is a folder" in one_error_line(capsys)


@pytest.fixture(scope="module")
def truncated(episode_path, tmp_path_factory):
    """The episode cut at 40 % of its size, as a killed writer leaves it."""
    cut = tmp_path_factory.mktemp("cut") / "cut.mcap"
    data = episode_path.read_bytes()
    cut.write_bytes(data[: int(len(data) * 0.4)])
    return cut


@pytest.mark.parametrize(
    "command",
    [
        ["summary"],
        ["plot", "--out", "x.png"],
        ["reestimate", "--method", "default"],
        ["export", "--lerobot", "dataset"],
    ],
)
def test_a_truncated_file_says_how_much_it_read(command, truncated, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main([command[0], str(truncated), *command[1:]]) == 2
    err = one_error_line(capsys)
    size = truncated.stat().st_size
    assert "is truncated" in err and f"of {size} bytes" in err and "read " in err
    read = int(err.split("read ")[1].split(" of ")[0])
    assert 0 < read <= size
    assert "--allow-truncated" in err and "replay repair" in err
    assert not (tmp_path / "x.png").exists() and not (tmp_path / "dataset").exists()


def test_a_truncated_file_is_read_up_to_its_cut_when_allowed(truncated, capsys):
    assert main(["summary", str(truncated), "--allow-truncated"]) == 0
    captured = capsys.readouterr()
    assert captured.err.startswith("replay: warning: ") and captured.err.count("\n") == 1
    assert "file: truncated: read " in captured.out
    assert "outcome: none written" in captured.out


def test_a_missing_subcommand_or_argument_is_a_usage_error(episode_path, capsys):
    for argv in ([], ["plot", str(episode_path)], ["reestimate", str(episode_path)]):
        with pytest.raises(SystemExit) as stop:
            main(argv)
        assert stop.value.code == 2
    capsys.readouterr()


def test_an_episode_given_twice_is_refused(episode_path, tmp_path, capsys):
    with pytest.raises(SystemExit) as stop:
        main(["export", str(episode_path), str(episode_path), "--lerobot", str(tmp_path / "d")])
    assert stop.value.code == 2
    assert "given twice" in capsys.readouterr().err
    assert not (tmp_path / "d").exists()


def test_the_copy_of_an_episode_reads_alike(episode_path, tmp_path):
    copy = tmp_path / "copy.mcap"
    shutil.copyfile(episode_path, copy)
    assert read_episode(copy).counts == read_episode(episode_path).counts


def test_repair_finishes_a_truncated_file_that_the_tools_then_read(truncated, tmp_path, capsys):
    out = tmp_path / "repaired.mcap"
    assert main(["repair", str(truncated), "--out", str(out)]) == 0
    said = capsys.readouterr().out
    assert f"of {truncated.stat().st_size} bytes" in said and "marked incomplete" in said
    assert main(["summary", str(out)]) == 0
    summary = capsys.readouterr().out
    assert "file: incomplete: repaired from a file cut short" in summary
    assert main(["repair", str(truncated), "--out", str(out)]) == 2  # never over a file
    assert "exists" in one_error_line(capsys)


def test_repair_refuses_a_finished_file(episode_path, tmp_path, capsys):
    assert main(["repair", str(episode_path), "--out", str(tmp_path / "r.mcap")]) == 2
    assert "already finished" in one_error_line(capsys)
    assert not (tmp_path / "r.mcap").exists()


def test_a_truncated_file_reestimates_exactly_up_to_its_cut(truncated, capsys):
    assert main(["reestimate", str(truncated), "--method", "default", "--allow-truncated"]) == 0
    report = capsys.readouterr().out
    counts = read_episode(truncated).counts
    frames, logged = counts["/tactile/image"], counts["/tactile/wrench"]
    assert logged > 20 and frames - logged in (0, 1)  # the cut may fall between the two
    assert f"re-estimated {frames} frames" in report
    assert f"over {logged} frames, {logged} of {logged} frames identical" in report


def _messages_in_chunks_over(path, damaged):
    """The messages of ``path`` in the chunks that ``damaged``'s zeroed bytes overlap (the
    ``damaged`` fixture's range), by the chunks' log-time ranges."""
    with path.open("rb") as handle:
        chunks = make_reader(handle).get_summary().chunk_indexes
    start = int(damaged.stat().st_size * 0.4)
    end = start + 100_000
    hit = [c for c in chunks if start < c.chunk_start_offset + c.chunk_length and
           c.chunk_start_offset < end]  # fmt: skip
    return [
        m
        for m in read_episode(path).records()[2]
        if any(c.message_start_time <= m.log_time <= c.message_end_time for c in hit)
    ]


@pytest.fixture(scope="module")
def damaged(episode_path, tmp_path_factory):
    """The episode with 100 kB zeroed at 40 % of its size (its footer and later chunks
    intact), as ``dd ... conv=notrunc`` leaves it."""
    path = tmp_path_factory.mktemp("damaged") / "damaged.mcap"
    data = bytearray(episode_path.read_bytes())
    start = int(len(data) * 0.4)
    data[start : start + 100_000] = bytes(100_000)
    path.write_bytes(bytes(data))
    return path


@pytest.mark.parametrize(
    "command",
    [
        ["summary"],
        ["plot", "--out", "x.png"],
        ["reestimate", "--method", "default"],
        ["export", "--lerobot", "dataset"],
    ],
)
def test_a_damaged_file_names_the_lost_bytes_in_one_line(command, damaged, tmp_path, capsys,
                                                         monkeypatch):  # fmt: skip
    monkeypatch.chdir(tmp_path)
    assert main([command[0], str(damaged), *command[1:]]) == 2
    err = one_error_line(capsys)
    start = int(damaged.stat().st_size * 0.4)
    assert "is damaged" in err and "truncated" not in err and "--allow-damaged" in err
    lost = err.split("(bytes ")[1].split(" ")[0]
    first, end = (int(x) for x in lost.split(".."))
    assert first <= start and start + 100_000 <= end
    assert not (tmp_path / "x.png").exists() and not (tmp_path / "dataset").exists()


def test_a_damaged_file_is_read_past_its_damage_and_repair_keeps_every_intact_chunk(
    damaged, episode_path, tmp_path, capsys
):
    assert main(["summary", str(damaged), "--allow-damaged"]) == 0
    captured = capsys.readouterr()
    assert captured.err.startswith("replay: warning: ") and captured.err.count("\n") == 1
    assert "file: damaged: " in captured.out and "outcome: done" in captured.out
    whole, read = read_episode(episode_path), read_episode(damaged)
    lost = sum(whole.counts.values()) - sum(read.counts.values())
    assert 0 < lost <= len(_messages_in_chunks_over(episode_path, damaged))  # those chunks only
    last = read.time_range_s()[1]
    assert last == whole.time_range_s()[1]  # read to the end, past the damage
    out = tmp_path / "repaired.mcap"
    assert main(["repair", str(damaged), "--out", str(out)]) == 0
    assert "bytes lost to damage" in capsys.readouterr().out
    assert read_episode(out).counts == read.counts
    assert main(["plot", str(out), "--out", str(tmp_path / "p.png")]) == 0


def test_an_episode_without_ticks_says_so_and_plot_refuses(tmp_path, capsys):
    from controller.episode.writer import EpisodeWriter

    path = tmp_path / "e.mcap"
    EpisodeWriter(path, {"format_version": "2", "task": "usb_c"}).close({"reason": "signal"})
    assert main(["summary", str(path)]) == 0
    out = capsys.readouterr().out
    assert "nan" not in out and "duration: none: no messages" in out and "ticks: none" in out
    assert main(["plot", str(path), "--out", str(tmp_path / "p.png")]) == 2
    assert "no control ticks" in one_error_line(capsys)
    assert not (tmp_path / "p.png").exists()


@pytest.mark.parametrize(
    "argv",
    [
        ["export", "EP", "--lerobot", "d", "--task", ""],
        ["export", "EP", "--lerobot", "d", "--task", "   "],
        ["reestimate", "EP", "--method", ""],
    ],
)
def test_an_empty_task_sentence_or_method_is_refused(argv, episode_path, tmp_path, capsys,
                                                     monkeypatch):  # fmt: skip
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as stop:
        main([str(episode_path) if a == "EP" else a for a in argv])
    assert stop.value.code == 2
    assert "empty text" in capsys.readouterr().err
    assert not (tmp_path / "d").exists()


@pytest.mark.parametrize(
    "payload, said",
    [(b"{broken", "does not decode as json"), (b'{"index": 0}', "no field 'start_s'"),
     (b"[1, 2]", "expected a JSON object")],
)  # fmt: skip
def test_a_hand_made_episode_with_bad_messages_is_one_line(payload, said, tmp_path, capsys):
    from mcap.writer import Writer

    from controller.episode.topics import PROFILE

    path = tmp_path / "hand.mcap"
    with path.open("wb") as stream:
        writer = Writer(stream)
        writer.start(profile=PROFILE, library="hand")
        channel = writer.register_channel("/loop/tick", "json", 0)
        writer.add_message(channel, 10_000_000, payload, 10_000_000, 0)
        writer.add_metadata("outcome", {"reason": "done"})
        writer.finish()
    assert main(["plot", str(path), "--out", str(tmp_path / "p.png")]) == 2
    err = one_error_line(capsys)
    assert str(path) in err and said in err
