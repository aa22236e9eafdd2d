"""The episode writer's listeners (the live view's and the Foxglove stream's seam): each gets
every record the file gets, with the same bytes, on the writer's thread; one that raises is
dropped and the recording goes on."""

from __future__ import annotations

import threading

from controller.episode import read_episode
from controller.episode.topics import LOOP_TICK, TRANSITION
from controller.episode.writer import EpisodeWriter, json_bytes


def tick(i):
    return {"index": i, "start_s": i * 0.01, "phase": "teleop"}


def test_a_listener_gets_every_record_with_the_files_bytes_on_the_writers_thread(tmp_path):
    got = []

    def listener(topic, t_ns, payload, data):
        got.append((topic.name, t_ns, payload, data, threading.current_thread().name))

    writer = EpisodeWriter(tmp_path / "e.mcap", {"format_version": "2"}, listeners=[listener])
    for i in range(5):
        writer.log(LOOP_TICK, i * 0.01, json_bytes, tick(i))
    writer.close({"reason": "done"})

    assert [g[2] for g in got] == [tick(i) for i in range(5)]  # the loop's own payloads
    assert {g[4] for g in got} == {"episode-writer"}
    messages = list(read_episode(tmp_path / "e.mcap").messages("/loop/tick"))
    assert [json_bytes(m.value) for m in messages] == [g[3] for g in got]
    assert [round(m.t_s * 1e9) + writer.offset_ns for m in messages] == [g[1] for g in got]


def test_a_listener_that_raises_is_dropped_and_the_recording_goes_on(tmp_path, caplog):
    calls = []

    def broken(topic, t_ns, payload, data):
        calls.append(topic.name)
        raise RuntimeError("the view went away")

    good = []
    writer = EpisodeWriter(
        tmp_path / "e.mcap",
        {"format_version": "2"},
        listeners=[broken, lambda *record: good.append(record[0].name)],
    )
    for i in range(3):
        writer.log(LOOP_TICK, i * 0.01, json_bytes, tick(i))
    writer.log(TRANSITION, 0.05, json_bytes, {"t_s": 0.05, "from": "a", "to": "b", "reason": "r"})
    writer.close({"reason": "done"})

    assert calls == ["/loop/tick"]  # called once, then dropped
    assert good == ["/loop/tick"] * 3 + ["/machine/transition"]
    assert read_episode(tmp_path / "e.mcap").counts == {"/loop/tick": 3, "/machine/transition": 1}
    assert "listener dropped: RuntimeError: the view went away" in caplog.text
