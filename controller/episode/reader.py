"""Reading an episode file: ``read_episode(path) -> Episode``.

The file is read once, front to back, record by record (controller/episode/scan.py, each
record parsed by ``mcap``), so the same code reads a finished file, one cut short by a
killed process and one damaged in the middle: reading stops at the file's cut (a record
cut in half) and reads on past damage (a chunk whose bytes or CRC are wrong is skipped
whole; after a broken record, reading resumes where records read whole again). The
episode says how much of the file it read (``read_bytes`` of ``size_bytes``), which byte
ranges were lost (``lost``), whether the file was finished (``finished``: its footer was
read) and complete (``complete``: finished by the writer, not by ``repair``, nothing
lost). Messages are kept as bytes and decoded when iterated: ``json`` topics to dicts,
Foxglove's ``protobuf`` topics to the protobuf messages of the schemas the file carries
(``mcap-protobuf-support``). Times are on the loop's clock, in s: a file's log times are
the wall clock (format 2), the loop's time plus the offset in its ``episode`` metadata
(``log_time_offset_ns``), which the reader subtracts (format 1: log times on the loop's
clock, offset 0). A JSON message of format 2 leaves out a field that has no value; the
reader gives every field of its schema that it lacks as None (format 1 wrote null).

Errors are ``EpisodeError`` (a ValueError), one line naming the file: a missing or
unreadable file, a file that is not MCAP, an MCAP file that is not an episode, a message
that does not decode.
"""

from __future__ import annotations

import json
import math
from collections import Counter
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from mcap.records import Attachment, Channel, Header, Message, Metadata, Schema, Statistics
from mcap_protobuf.decoder import DecoderFactory

from controller.episode.scan import LostRange, NotMcap, scan_records
from controller.episode.topics import (
    FORMAT_VERSION,
    METADATA_EPISODE,
    METADATA_OUTCOME,
    METADATA_REPAIR,
    PROFILE,
    READABLE_VERSIONS,
)

NS_PER_S = 1_000_000_000


class EpisodeError(ValueError):
    """An episode file that cannot be read (one line, naming the file)."""


@dataclass(frozen=True)
class EpisodeMessage:
    """One decoded message: ``topic``, ``t_s`` (its log time on the loop's clock, s: the
    log time minus the episode's ``offset_ns``),
    ``sequence`` (the MCAP record's: this project's writer numbers each topic's messages on
    its own, earlier ones one sequence across topics) and ``value`` (a dict for
    a ``json`` topic; a protobuf message of the Foxglove schema for a ``protobuf`` one)."""

    topic: str
    t_s: float
    sequence: int
    value: Any


@dataclass
class Episode:
    """A read episode (see the module doc).

    ``metadata``: the MCAP metadata records by name (``episode`` at the start, ``outcome``
    at the end, ``repair`` if repaired: controller/episode/topics.py); ``attachments``: by
    name (``task.yaml``; ``attachment_media``: their media types); ``counts``: messages
    per topic; ``finished``: the footer was read;
    ``complete``: finished by the writer (``outcome`` written, not repaired, nothing lost);
    ``read_bytes`` / ``size_bytes``: where the file's readable records end, and its size;
    ``lost``: the byte ranges that held no readable record (damage), in file order;
    ``expected_messages``: the message count the writer's statistics give (None when they
    were not read); ``data_crc_matches``: the data section's CRC against its bytes (None
    when not recorded; see ``unverified_change``).
    """

    path: Path
    metadata: dict[str, dict[str, str]]
    attachments: dict[str, bytes]
    counts: dict[str, int]
    finished: bool
    read_bytes: int
    size_bytes: int
    _schemas: dict[int, Schema] = field(repr=False)
    _channels: dict[int, Channel] = field(repr=False)
    _messages: list[Message] = field(repr=False)
    _decoders: dict[int, Callable[[bytes], Any]] = field(default_factory=dict, repr=False)
    lost: tuple[LostRange, ...] = ()
    expected_messages: int | None = None
    attachment_media: dict[str, str] = field(default_factory=dict)
    data_crc_matches: bool | None = None

    @property
    def unverified_change(self) -> bool:
        """No byte range was lost, yet the data section's CRC does not match its bytes: a
        byte changed outside the chunks (metadata, message indexes), read as it stands."""
        return not self.lost and self.data_crc_matches is False

    @property
    def damaged(self) -> bool:
        """Some bytes held no readable record (``lost`` is not empty)."""
        return bool(self.lost)

    @property
    def lost_bytes(self) -> int:
        return sum(r.size for r in self.lost)

    def lost_text(self, most: int = 3) -> str:
        """The lost ranges in words: ``bytes A..B (N bytes: REASON)``, the first ``most``."""
        shown = [f"bytes {r.start}..{r.end} ({r.size} bytes: {r.reason})" for r in self.lost[:most]]
        more = len(self.lost) - most
        return "; ".join(shown) + (f"; and {more} more ranges" if more > 0 else "")

    @property
    def complete(self) -> bool:
        return (
            self.finished
            and METADATA_OUTCOME in self.metadata
            and METADATA_REPAIR not in self.metadata
            and not self.lost
        )

    @property
    def offset_ns(self) -> int:
        """The offset from the loop's clock to the log times (the wall clock), integer ns
        (metadata ``log_time_offset_ns``; 0 in files of format 1, logged on the loop's
        clock): a log time minus it is the loop's time."""
        return int(self.info.get("log_time_offset_ns", "0"))

    def loop_s(self, log_time_ns: int) -> float:
        """A log time (ns) on the loop's clock, s."""
        return (log_time_ns - self.offset_ns) / NS_PER_S

    @property
    def info(self) -> dict[str, str]:
        """The ``episode`` metadata (task, seed, controller, versions, machine, ...)."""
        return self.metadata.get(METADATA_EPISODE, {})

    @property
    def outcome(self) -> dict[str, str] | None:
        """The ``outcome`` metadata, None if the run never wrote it (killed)."""
        return self.metadata.get(METADATA_OUTCOME)

    @property
    def topics(self) -> list[str]:
        """The topics with at least one message, sorted."""
        return sorted(self.counts)

    def time_range_s(self) -> tuple[float, float]:
        """The first and last log time, s (NaN, NaN without messages)."""
        if not self._messages:
            return (math.nan, math.nan)
        times = [m.log_time for m in self._messages]
        return (self.loop_s(min(times)), self.loop_s(max(times)))

    def messages(self, *topics: str) -> Iterator[EpisodeMessage]:
        """The messages of ``topics`` (every topic if none), decoded, in log time order and,
        among messages of equal log time, in the file's order: the order the loop produced
        them (the writer writes them in that order)."""
        wanted = set(topics)
        ids = {cid for cid, ch in self._channels.items() if not wanted or ch.topic in wanted}
        chosen = [m for m in self._messages if m.channel_id in ids]  # in the file's order
        chosen.sort(key=lambda m: m.log_time)  # stable: the file's order among equal times
        offset_ns = self.offset_ns
        for record in chosen:
            channel = self._channels[record.channel_id]
            try:
                value = self._decoder(channel)(record.data)
            except EpisodeError:
                raise
            except Exception as error:  # noqa: BLE001 -- a decoder's own errors, any type
                raise EpisodeError(
                    f"episode '{self.path}': topic {channel.topic}, message at "
                    f"{(record.log_time - offset_ns) / NS_PER_S:.6f} s: does not decode as "
                    f"{channel.message_encoding} ({' '.join(str(error).split())[:160]})"
                ) from None
            if channel.message_encoding == "json" and not isinstance(value, dict):
                raise EpisodeError(
                    f"episode '{self.path}': topic {channel.topic}, message at "
                    f"{(record.log_time - offset_ns) / NS_PER_S:.6f} s: expected a JSON "
                    f"object, got {type(value).__name__}"
                )
            t_s = (record.log_time - offset_ns) / NS_PER_S
            yield EpisodeMessage(channel.topic, t_s, record.sequence, value)

    def records(self) -> tuple[dict[int, Schema], dict[int, Channel], list[Message]]:
        """The raw MCAP schemas and channels by id and the messages in file order (what
        ``repair`` copies)."""
        return self._schemas, self._channels, self._messages

    def _decoder(self, channel: Channel) -> Callable[[bytes], Any]:
        decoder = self._decoders.get(channel.id)
        if decoder is None:
            if channel.message_encoding == "json":
                decoder = self._json_decoder(channel)
            else:
                found = DecoderFactory().decoder_for(
                    channel.message_encoding, self._schemas.get(channel.schema_id)
                )
                if found is None:
                    raise EpisodeError(
                        f"episode '{self.path}': topic {channel.topic}: no decoder for "
                        f"encoding {channel.message_encoding!r}"
                    )
                decoder = found
            self._decoders[channel.id] = decoder
        return decoder

    def _json_decoder(self, channel: Channel) -> Callable[[bytes], Any]:
        """``json.loads``; in format 2, the schema's fields a message lacks set to None."""
        if self.info.get("format_version", "1").split(".")[0] == "1":
            return json.loads
        schema = self._schemas.get(channel.schema_id)
        try:
            fields = tuple(json.loads(schema.data)["properties"]) if schema else ()
        except (ValueError, TypeError, KeyError):
            fields = ()

        def decode(data: bytes) -> Any:
            value = json.loads(data)
            if isinstance(value, dict):
                for name in fields:
                    value.setdefault(name, None)
            return value

        return decode


def read_episode(path: str | Path) -> Episode:
    """Read the episode at ``path`` (see the module doc); EpisodeError if it is missing, not
    MCAP, or not an episode."""
    path = Path(path)
    if path.is_dir():
        raise EpisodeError(f"episode '{path}': a folder; expected an episode file (.mcap)")
    try:
        handle = path.open("rb")
    except OSError as error:
        raise EpisodeError(f"episode '{path}': cannot open: {error.strerror}") from None
    state = _Scan(path)
    with handle:
        try:
            scan = scan_records(handle, state.take)
        except NotMcap as error:
            raise EpisodeError(f"episode '{path}': not an MCAP file ({error})") from None
        except OSError as error:
            raise EpisodeError(f"episode '{path}': cannot read: {error.strerror}") from None
    episode = state.episode(scan.read_bytes, scan.finished, tuple(scan.lost))
    episode.data_crc_matches = scan.data_crc_matches
    return episode


@dataclass
class _Scan:
    """What one pass over the file's records collects."""

    path: Path
    metadata: dict[str, dict[str, str]] = field(default_factory=dict)
    attachments: dict[str, bytes] = field(default_factory=dict)
    attachment_media: dict[str, str] = field(default_factory=dict)
    schemas: dict[int, Schema] = field(default_factory=dict)
    channels: dict[int, Channel] = field(default_factory=dict)
    messages: list[Message] = field(default_factory=list)
    statistics: Statistics | None = None

    def take(self, record: Any) -> None:
        if isinstance(record, Header):
            if record.profile != PROFILE:
                raise EpisodeError(
                    f"episode '{self.path}': an MCAP file but not an episode "
                    f"(profile {record.profile!r}, expected {PROFILE!r})"
                )
        elif isinstance(record, Schema):
            self.schemas[record.id] = record
        elif isinstance(record, Channel):
            self.channels[record.id] = record
        elif isinstance(record, Message):
            self.messages.append(record)
        elif isinstance(record, Metadata):
            self.metadata[record.name] = dict(record.metadata)
        elif isinstance(record, Attachment):
            self.attachments[record.name] = bytes(record.data)
            self.attachment_media[record.name] = record.media_type
        elif isinstance(record, Statistics):
            self.statistics = record

    def episode(self, read_bytes: int, finished: bool, lost: tuple[LostRange, ...]) -> Episode:
        version = self.metadata.get(METADATA_EPISODE, {}).get("format_version")
        if version is not None and version.split(".")[0] not in READABLE_VERSIONS:
            raise EpisodeError(
                f"episode '{self.path}': format version {version}, this reader reads "
                f"{' and '.join(READABLE_VERSIONS)} (the newest: {FORMAT_VERSION})"
            )
        known = [m for m in self.messages if m.channel_id in self.channels]
        counts = Counter(self.channels[m.channel_id].topic for m in known)
        return Episode(
            self.path,
            self.metadata,
            self.attachments,
            dict(counts),
            finished,
            read_bytes,
            self.path.stat().st_size,
            self.schemas,
            self.channels,
            known,
            lost=lost,
            expected_messages=(
                None if self.statistics is None else int(self.statistics.message_count)
            ),
            attachment_media=self.attachment_media,
        )


def decode_image(value: Any) -> np.ndarray:
    """A ``/tactile/image`` message's image as the estimator took it: uint8 BGR (H x W x 3)
    or grey (H x W). ValueError if the bytes are not an image."""
    data = np.frombuffer(value.data, np.uint8)
    image = cv2.imdecode(data, cv2.IMREAD_UNCHANGED)
    if image is None:
        raise ValueError(f"tactile image: cannot decode its {value.format!r} bytes")
    return image


def grid_arrays(value: Any) -> Mapping[str, np.ndarray]:
    """A ``foxglove.Grid`` message's fields as (rows, cols) float arrays by name (for
    ``/tactile/field``: ``u_mm``, ``v_mm``, ``div``), row 0 first."""
    cols = value.column_count
    rows = len(value.data) // value.row_stride
    out: dict[str, np.ndarray] = {}
    for f in value.fields:
        if f.type != 7:  # PackedElementField.FLOAT32
            raise ValueError(f"grid field {f.name!r}: expected float32, got type {f.type}")
        strided = np.frombuffer(value.data, np.uint8).reshape(rows, value.row_stride)
        cells = strided[:, : cols * value.cell_stride].reshape(rows, cols, value.cell_stride)
        out[f.name] = cells[:, :, f.offset : f.offset + 4].copy().view("<f4")[:, :, 0]
    return out
