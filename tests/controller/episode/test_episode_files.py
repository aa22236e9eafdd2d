"""The episode writer's queue overflow, and the reader on bad, foreign and truncated files."""

from __future__ import annotations

import errno
import json
import resource
import signal
import threading
import time

import numpy as np
import pytest
from mcap.writer import Writer

from controller.episode import EpisodeError, decode_image, read_episode
from controller.episode.foxglove_types import encode_image
from controller.episode.recorder import RecordingSource, arm_json
from controller.episode.repair import repair
from controller.episode.topics import (
    ARM_STATUS,
    COMMAND,
    JSON_SCHEMAS,
    LOOP_TICK,
    TACTILE_PUSH,
    TRANSITION,
)
from controller.episode.writer import EpisodeWriter, json_bytes
from controller.tactile.wrench import WrenchEstimate
from core.clock import ManualClock
from core.config import CONFIG_ROOT
from core.devices import ArmMode, ArmState, ArmStatus, Pose
from drivers.registry import load_device_config
from drivers.sim.twins.tactile import SimTactileSensor

MINI_CAMERA = load_device_config(CONFIG_ROOT / "sensors" / "gelsight_mini_camera.yaml").config


def _writer(path, **options):
    return EpisodeWriter(path, {"format_version": "2", "seed": "0"}, **options)


def test_a_full_queue_drops_counts_and_records_what_it_dropped(tmp_path):
    started, release = threading.Event(), threading.Event()

    def slow(payload):  # the logger thread stalls on its first record
        started.set()
        release.wait(10.0)
        return json_bytes(payload)

    writer = _writer(tmp_path / "e.mcap", queue_size=3)
    for i in range(20):
        writer.log(LOOP_TICK, i * 0.01, slow, {"index": i, "start_s": i * 0.01, "phase": "grasp"})
        if i == 0:
            assert started.wait(10.0)
    writer.log(TRANSITION, 0.5, json_bytes, {"t_s": 0.5, "from": "a", "to": "b", "reason": "r"})
    dropped = writer.dropped_total
    release.set()
    writer.close({"reason": "done"})

    assert dropped == 17  # of 21: one in the thread's hands, three queued
    ep = read_episode(tmp_path / "e.mcap")
    assert ep.data_crc_matches is True  # the writer records the data section's CRC
    assert ep.counts["/loop/tick"] + writer.dropped["/loop/tick"] == 20
    assert ep.counts.get("/machine/transition", 0) + writer.dropped["/machine/transition"] == 1
    assert ep.outcome["dropped_total"] == str(dropped)
    drops = [m.value for m in ep.messages("/episode/drops")]
    assert drops[-1]["dropped_total"] == dropped
    assert drops[-1]["by_topic"] == dict(writer.dropped)
    indices = [m.value["index"] for m in ep.messages("/loop/tick")]
    assert indices == sorted(indices)


def test_messages_of_equal_time_read_back_in_the_order_logged_across_topics(tmp_path):
    order = [(COMMAND, 0.0), (LOOP_TICK, 0.0), (TACTILE_PUSH, 0.0), (COMMAND, 0.01),
             (TACTILE_PUSH, 0.01), (LOOP_TICK, 0.01), (TRANSITION, 0.01), (TACTILE_PUSH, 0.01),
             (LOOP_TICK, 0.005)]  # fmt: skip
    writer = _writer(tmp_path / "e.mcap")
    for i, (topic, t_s) in enumerate(order):
        writer.log(topic, t_s, json_bytes, {"i": i})
        if i == 4:
            writer.flush_soon()  # across a chunk's end too
            time.sleep(0.05)
    writer.close({"reason": "done"})
    expected = sorted(range(len(order)), key=lambda i: order[i][1])  # stable: logged order
    ep = read_episode(tmp_path / "e.mcap")
    assert [m.value["i"] for m in ep.messages()] == expected
    cut = tmp_path / "cut.mcap"  # the same after ``repair``
    cut.write_bytes((tmp_path / "e.mcap").read_bytes()[:-200])
    repair(cut, tmp_path / "fixed.mcap")
    assert [m.value["i"] for m in read_episode(tmp_path / "fixed.mcap").messages()] == expected


def test_a_failed_write_stops_the_writer_and_close_raises_its_oserror(tmp_path):
    path = tmp_path / "e.mcap"
    writer = _writer(path)
    time.sleep(0.1)  # the header written
    limit = path.stat().st_size + 20_000  # the file may not grow past this: EFBIG
    soft, hard = resource.getrlimit(resource.RLIMIT_FSIZE)
    handler = signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # the write fails, no signal
    resource.setrlimit(resource.RLIMIT_FSIZE, (limit, hard))
    try:
        noise = np.random.default_rng(0).integers(0, 256, 4000, np.uint8).tobytes()
        for i in range(200):  # 800 kB that zstd cannot shrink, flushed every 0.1 s
            writer.log(LOOP_TICK, i * 0.01, lambda _: noise, None)
            time.sleep(0.002)
        time.sleep(0.2)
        writer.log(LOOP_TICK, 3.0, json_bytes, {"index": 0})  # after the failure: dropped
        with pytest.raises(OSError) as failure:
            writer.close({"reason": "done"})
    finally:
        resource.setrlimit(resource.RLIMIT_FSIZE, (soft, hard))
        signal.signal(signal.SIGXFSZ, handler)
    assert failure.value.errno == errno.EFBIG and failure.value.filename == str(path)
    assert writer.dropped["/loop/tick"] >= 1
    ep = read_episode(path)  # what was written before the failure reads
    assert not ep.finished and 0 < ep.counts["/loop/tick"] < 200


class _Zero:
    """A wrench source that answers every frame with a zero estimate."""

    def push(self, frame, t_s):
        return WrenchEstimate.zero(t_s, zeroing=False, calibrated=False)

    def capture_open(self, n_frames=None):
        pass

    def rezero(self, n_frames=None):
        pass


@pytest.mark.parametrize("image_format", ["jpeg", "png"])
def test_the_cameras_jpeg_is_logged_as_it_comes_and_any_other_frame_is_encoded(
    tmp_path, image_format
):
    clock = ManualClock()
    camera = SimTactileSensor(MINI_CAMERA, clock, np.random.default_rng(0))
    writer = _writer(tmp_path / "e.mcap")
    with camera:
        tap = RecordingSource(_Zero(), writer, clock, image_format=image_format,
                              jpeg_quality=80, camera=camera)  # fmt: skip
        clock.advance(0.04)
        frame = camera.read_latest(0.1)
        tap.push(frame.image, frame.t_s)  # the camera's JPEG, if it made one
        tap.push(frame.image.copy(), frame.t_s)  # not the frame handed over: encoded here
    writer.close({"reason": "done"})
    first, second = (m.value for m in read_episode(tmp_path / "e.mcap").messages("/tactile/image"))
    assert (frame.jpeg is not None) == (image_format == "jpeg")  # asked for by a jpeg episode
    if image_format == "jpeg":
        assert first.data == frame.jpeg == encode_image(frame.image, "jpeg", 80) == second.data
    else:
        np.testing.assert_array_equal(decode_image(first), frame.image)  # lossless
        assert first.data == second.data


def test_a_missing_file_is_one_line_naming_it(tmp_path):
    with pytest.raises(EpisodeError, match=r"episode '.*nope.mcap': cannot open") as error:
        read_episode(tmp_path / "nope.mcap")
    assert "\n" not in str(error.value)


def test_a_foreign_file_is_refused(tmp_path):
    foreign = tmp_path / "notes.mcap"
    foreign.write_bytes(b"this is not an MCAP file at all")
    with pytest.raises(EpisodeError, match="not an MCAP file"):
        read_episode(foreign)
    other = tmp_path / "other.mcap"
    with other.open("wb") as handle:
        mcap = Writer(handle)
        mcap.start(profile="ros2", library="test")
        mcap.finish()
    with pytest.raises(EpisodeError, match="not an episode .profile 'ros2'"):
        read_episode(other)


def test_a_truncated_file_reads_to_its_last_whole_record_and_says_how_much(tmp_path):
    path = tmp_path / "e.mcap"
    writer = _writer(path, flush_interval_s=0.01)
    for i in range(200):
        writer.log(LOOP_TICK, i * 0.01, json_bytes, {"index": i, "start_s": i * 0.01, "phase": "x"})
        if i % 50 == 49:
            threading.Event().wait(0.05)  # flushed by then (every 0.01 s)
    writer.close({"reason": "done"})
    whole = path.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(whole[: len(whole) // 2])

    ep = read_episode(cut)
    assert not ep.finished and not ep.complete
    assert 0 < ep.read_bytes < ep.size_bytes == len(whole) // 2
    indices = [m.value["index"] for m in ep.messages("/loop/tick")]
    assert 0 < len(indices) < 200 and indices == list(range(len(indices)))

    report = repair(cut, tmp_path / "fixed.mcap")
    assert (report.read_bytes, report.source_bytes) == (ep.read_bytes, ep.size_bytes)
    assert read_episode(tmp_path / "fixed.mcap").counts == ep.counts
    with pytest.raises(EpisodeError, match="already finished and whole"):
        repair(path, tmp_path / "again.mcap")
    with pytest.raises(EpisodeError, match="is the episode itself"):
        repair(cut, cut)


def test_a_file_cut_inside_its_header_is_not_an_episode(tmp_path):
    path = tmp_path / "e.mcap"
    _writer(path).close()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(path.read_bytes()[:12])
    with pytest.raises(EpisodeError, match="not an MCAP file"):
        read_episode(cut)


def test_a_record_its_encoder_refuses_is_dropped_and_counted_and_writing_goes_on(tmp_path):
    writer = _writer(tmp_path / "e.mcap")
    writer.log(LOOP_TICK, 0.0, json_bytes, {"index": 0, "start_s": 0.0, "phase": "x"})
    writer.log(LOOP_TICK, 0.01, json_bytes, {"index": 1, "start_s": object(), "phase": "x"})
    writer.log(LOOP_TICK, 0.02, json_bytes, {"index": 2, "start_s": 0.02, "phase": "x"})
    writer.close({"reason": "done"})
    ep = read_episode(tmp_path / "e.mcap")
    assert [m.value["index"] for m in ep.messages("/loop/tick")] == [0, 2]
    assert ep.complete and ep.outcome["dropped_total"] == "1"


def test_json_leaves_out_what_has_no_value_and_writes_numpy_values_as_numbers():
    payload = {
        "a": float("nan"),
        "b": np.array([1.5, np.inf]),
        "c": np.float32(0.25),
        "d": None,
        "e": "null",
        "f": [1, 2],
    }
    assert json.loads(json_bytes(payload)) == {"c": 0.25, "e": "null", "f": [1, 2]}
    assert json_bytes({"g": 1.0}) == b'{"g":1.0}'


def test_the_reader_gives_the_fields_a_message_lacks_as_none(tmp_path):
    writer = _writer(tmp_path / "e.mcap")
    writer.log(LOOP_TICK, 0.0, json_bytes, {"index": 0, "start_s": 0.0, "phase": "x",
                                           "fault": None})  # fmt: skip
    writer.close({"reason": "done"})
    (message,) = read_episode(tmp_path / "e.mcap").messages("/loop/tick")
    assert message.value["fault"] is None and message.value["overran"] is None
    assert message.value["phase"] == "x"


@pytest.mark.parametrize("force", [(0.5, -1.0, 4.25), None])
def test_the_arm_status_carries_the_external_force_or_null(force):
    status = ArmStatus(
        t_s=1.0,
        tcp=Pose((0.3, 0.0, 0.2), (3.0, 0.0, 0.1)),
        joints_rad=(0.0,) * 6,
        mode=ArmMode.SERVO,
        state=ArmState.MOVING,
        external_force_n=force,
    )
    message = json.loads(arm_json(status))
    assert message.get("external_force_n") == (None if force is None else list(force))
    assert set(message) <= set(JSON_SCHEMAS[ARM_STATUS.schema]["properties"])


def _hand_made(path, version, log_time_ns, payload):
    """An episode written with ``mcap``'s writer alone, as a reader of another version finds it."""
    with path.open("wb") as stream:
        mcap = Writer(stream)
        mcap.start(profile="tactile-insertion", library="test")
        mcap.add_metadata("episode", {"format_version": version})
        schema = mcap.register_schema("tactile_insertion.LoopTick", "jsonschema", b"{}")
        channel = mcap.register_channel("/loop/tick", "json", schema)
        mcap.add_message(channel, log_time_ns, json.dumps(payload).encode(), log_time_ns)
        mcap.finish()


def test_a_format_1_episode_reads_on_the_loops_clock_with_its_nulls(tmp_path):
    path = tmp_path / "old.mcap"
    _hand_made(path, "1", 1_500_000_000, {"index": 0, "start_s": 1.5, "fault": None})
    episode = read_episode(path)
    assert episode.offset_ns == 0
    (message,) = episode.messages("/loop/tick")
    assert message.t_s == 1.5 and message.value == {"index": 0, "start_s": 1.5, "fault": None}


def test_another_format_version_is_refused_in_one_line(tmp_path):
    path = tmp_path / "new.mcap"
    _hand_made(path, "3", 0, {"index": 0})
    with pytest.raises(EpisodeError, match=r"format version 3, this reader reads 1 and 2") as e:
        read_episode(path)
    assert "\n" not in str(e.value)


def test_log_times_are_the_wall_clock_and_messages_give_the_loops_time(tmp_path):
    before = time.time_ns()
    writer = EpisodeWriter(tmp_path / "e.mcap", {"format_version": "2"}, loop_now_s=100.0)
    writer.log(LOOP_TICK, 100.25, json_bytes, {"index": 0, "start_s": 100.25, "phase": "x"})
    writer.close({"reason": "done"})
    episode = read_episode(tmp_path / "e.mcap")
    (message,) = episode.messages("/loop/tick")
    assert message.t_s == 100.25 and episode.time_range_s() == (100.25, 100.25)
    (record,) = episode.records()[2]
    assert before + 0.25e9 <= record.log_time <= time.time_ns() + 0.25e9
    assert int(episode.info["log_time_offset_ns"]) == episode.offset_ns == writer.offset_ns
