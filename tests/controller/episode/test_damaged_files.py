"""The reader and ``repair`` on files damaged in the middle: bytes zeroed or overwritten
anywhere are read past, the lost byte ranges named, every intact chunk kept."""

from __future__ import annotations

import json
import random

import pytest
from mcap.reader import make_reader
from mcap.writer import CompressionType, Writer

from controller.episode import EpisodeError, read_episode
from controller.episode.repair import repair
from controller.episode.topics import METADATA_EPISODE, METADATA_OUTCOME, PROFILE

TICKS = 600
CHUNK_BYTES = 2048  # many small chunks: damage inside one leaves the others


def _episode(path, compression=CompressionType.ZSTD):
    """A small finished episode: /loop/tick messages in many chunks, its metadata and a
    task attachment, as the writer lays them out."""
    with path.open("wb") as stream:
        writer = Writer(
            stream, chunk_size=CHUNK_BYTES, compression=compression, enable_data_crcs=True
        )
        writer.start(profile=PROFILE, library="test")
        writer.add_metadata(METADATA_EPISODE, {"format_version": "2", "task": "usb_c"})
        writer.add_attachment(0, 0, "task.yaml", "application/yaml", b"task: usb_c\n")
        schema = writer.register_schema("loop.Tick", "jsonschema", b"{}")
        channel = writer.register_channel("/loop/tick", "json", schema)
        for i in range(TICKS):
            payload = {"index": i, "start_s": i * 0.01, "phase": "teleop", "pad": "x" * 40}
            ns = i * 10_000_000
            writer.add_message(channel, ns, json.dumps(payload).encode(), ns, i)
        writer.add_metadata(METADATA_OUTCOME, {"reason": "done"})
        writer.finish()
    return path


def _indices(episode):
    return [m.value["index"] for m in episode.messages("/loop/tick")]


def _damage(path, offset, data):
    with path.open("r+b") as handle:
        handle.seek(offset)
        handle.write(data)


@pytest.mark.parametrize("compression", [CompressionType.ZSTD, CompressionType.NONE])
def test_bytes_zeroed_in_the_middle_lose_only_their_chunks(tmp_path, compression):
    path = _episode(tmp_path / "e.mcap", compression)
    size = path.stat().st_size
    offset = size // 2
    _damage(path, offset, bytes(3000))

    ep = read_episode(path)
    assert ep.finished and ep.damaged and not ep.complete
    assert ep.read_bytes == ep.size_bytes == size
    (lost,) = ep.lost
    assert lost.start <= offset and offset + 3000 <= lost.end < size
    assert lost.size < 3000 + 3 * CHUNK_BYTES  # the zeroed bytes and the chunks they touch
    indices = _indices(ep)
    assert indices[0] == 0 and indices[-1] == TICKS - 1  # read past the damage to the end
    gap = [i for i in range(TICKS) if i not in set(indices)]
    assert gap == list(range(gap[0], gap[-1] + 1))  # one run of lost ticks
    assert 0 < len(gap) < TICKS // 4
    assert ep.expected_messages == TICKS
    assert ep.outcome == {"reason": "done"}


def test_twelve_bytes_overwritten_in_a_chunk_are_named_and_repair_keeps_the_rest(tmp_path):
    path = _episode(tmp_path / "e.mcap")
    offset = path.stat().st_size // 3
    _damage(path, offset, b"X" * 12)

    ep = read_episode(path)
    assert ep.finished  # the footer and the chunks after the damage were intact
    (lost,) = ep.lost
    assert lost.start <= offset < offset + 12 <= lost.end
    assert "bytes" in ep.lost_text() and str(lost.start) in ep.lost_text()

    report = repair(path, tmp_path / "fixed.mcap")
    fixed = read_episode(tmp_path / "fixed.mcap")
    assert report.messages == len(_indices(ep)) == len(_indices(fixed)) > TICKS * 3 // 4
    assert report.lost_bytes == lost.size
    assert fixed.finished and not fixed.damaged and not fixed.complete
    assert fixed.metadata["repair"]["lost_ranges"] == f"{lost.start}..{lost.end}"
    assert _indices(fixed) == _indices(ep)
    assert fixed.outcome == {"reason": "done"}


def test_repair_writes_the_attachments_media_type_as_the_writer_did(tmp_path):
    path = _episode(tmp_path / "e.mcap")
    _damage(path, path.stat().st_size // 2, b"X" * 12)
    repair(path, tmp_path / "fixed.mcap")
    with (tmp_path / "fixed.mcap").open("rb") as handle:
        attachments = list(make_reader(handle).iter_attachments())
    assert [(a.name, a.media_type) for a in attachments] == [("task.yaml", "application/yaml")]


def test_a_damaged_footer_or_summary_keeps_every_message(tmp_path):
    path = _episode(tmp_path / "e.mcap")
    size = path.stat().st_size
    _damage(path, size - 40, b"\xff" * 20)  # inside the footer
    ep = read_episode(path)
    assert _indices(ep) == list(range(TICKS))
    assert not ep.finished


def test_random_damage_never_raises_anything_but_a_one_line_episode_error(tmp_path):
    clean = _episode(tmp_path / "clean.mcap").read_bytes()
    rng = random.Random(7)
    for trial in range(40):
        data = bytearray(clean)
        offset = rng.randrange(len(data))
        length = rng.choice([1, 12, 300, 5000])
        data[offset : offset + length] = (bytes(length) if trial % 2 else rng.randbytes(length))[
            : len(data) - offset
        ]
        path = tmp_path / f"d{trial}.mcap"
        path.write_bytes(bytes(data))
        try:
            ep = read_episode(path)
            indices = _indices(ep)
        except EpisodeError as error:
            assert "\n" not in str(error) and str(path) in str(error)
            continue
        assert indices == sorted(indices)
        if offset > 100:  # past the header: at most the damaged stretch is lost
            assert len(indices) >= TICKS - (length // 60 + 3 * CHUNK_BYTES // 60)


def test_a_wrong_profile_is_not_called_a_file_that_is_not_mcap(tmp_path):
    other = tmp_path / "other.mcap"
    with other.open("wb") as handle:
        mcap = Writer(handle)
        mcap.start(profile="ros2", library="test")
        mcap.finish()
    with pytest.raises(EpisodeError) as error:
        read_episode(other)
    assert "not an MCAP file" not in str(error.value)
    assert "an MCAP file but not an episode (profile 'ros2'" in str(error.value)


def test_a_message_that_is_not_json_is_one_line_naming_topic_and_time(tmp_path):
    path = tmp_path / "e.mcap"
    with path.open("wb") as stream:
        writer = Writer(stream)
        writer.start(profile=PROFILE, library="test")
        channel = writer.register_channel("/loop/tick", "json", 0)
        writer.add_message(channel, 1_500_000_000, b"{not json", 0, 0)
        writer.finish()
    with pytest.raises(EpisodeError, match=r"topic /loop/tick, message at 1.500000 s") as error:
        list(read_episode(path).messages())
    assert "\n" not in str(error.value)


def test_a_byte_changed_outside_the_chunks_is_noticed_by_the_data_sections_crc(tmp_path):
    path = _episode(tmp_path / "e.mcap")
    data = bytearray(path.read_bytes())
    where = data.index(b"done")  # the outcome's metadata: no CRC of its own
    data[where] = ord("D")
    path.write_bytes(bytes(data))
    ep = read_episode(path)
    assert not ep.lost and ep.data_crc_matches is False and ep.unverified_change
    assert ep.outcome == {"reason": "Done"}  # read as it stands, and said to be unverified
    clean = read_episode(_episode(tmp_path / "clean.mcap"))
    assert clean.data_crc_matches is True and not clean.unverified_change
