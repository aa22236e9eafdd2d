"""Reading an episode file: ``read_episode(path) -> Episode``.

The file is read once, front to back, record by record (MCAP's stream reader), so the same
code reads a finished file and one cut short by a killed process: reading stops at the last
whole record (a record cut in half, a chunk whose bytes or CRC are wrong), and the episode
says how much of the file it read (``read_bytes`` of ``size_bytes``) and whether the file was
finished (``finished``: its footer was read) and complete (``complete``: finished by the
writer, not by ``repair``). Messages are kept as bytes and decoded when iterated:
``json`` topics to dicts, Foxglove's ``protobuf`` topics to the protobuf messages of the
schemas the file carries (``mcap-protobuf-support``). Times are on the loop's clock, in s.

Errors are ``EpisodeError`` (a ValueError), one line naming the file: a missing or
unreadable file, a file that is not MCAP, an MCAP file that is not an episode.
"""

from __future__ import annotations

import json
import math
import struct
from collections import Counter
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from mcap.exceptions import McapError
from mcap.records import Attachment, Channel, Chunk, Footer, Header, Message, Metadata, Schema
from mcap.stream_reader import StreamReader, breakup_chunk
from mcap_protobuf.decoder import DecoderFactory

from controller.episode.topics import (
    FORMAT_VERSION,
    METADATA_EPISODE,
    METADATA_OUTCOME,
    METADATA_REPAIR,
    PROFILE,
)

NS_PER_S = 1_000_000_000


class EpisodeError(ValueError):
    """An episode file that cannot be read (one line, naming the file)."""


@dataclass(frozen=True)
class EpisodeMessage:
    """One decoded message: ``topic``, ``t_s`` (its log time on the loop's clock, s),
    ``sequence`` (the writer's order among messages of equal time) and ``value`` (a dict for
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
    name (``task.yaml``); ``counts``: messages per topic; ``finished``: the footer was read;
    ``complete``: finished by the writer (``outcome`` written, not repaired);
    ``read_bytes`` / ``size_bytes``: how much of the file held whole records, and its size.
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

    @property
    def complete(self) -> bool:
        return (
            self.finished
            and METADATA_OUTCOME in self.metadata
            and METADATA_REPAIR not in self.metadata
        )

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
        return (min(times) / NS_PER_S, max(times) / NS_PER_S)

    def messages(self, *topics: str) -> Iterator[EpisodeMessage]:
        """The messages of ``topics`` (every topic if none), decoded, in (log time,
        sequence) order: the order the loop produced them."""
        wanted = set(topics)
        ids = {cid for cid, ch in self._channels.items() if not wanted or ch.topic in wanted}
        chosen = [m for m in self._messages if m.channel_id in ids]
        chosen.sort(key=lambda m: (m.log_time, m.sequence))
        for record in chosen:
            channel = self._channels[record.channel_id]
            yield EpisodeMessage(
                channel.topic,
                record.log_time / NS_PER_S,
                record.sequence,
                self._decoder(channel)(record.data),
            )

    def records(self) -> tuple[dict[int, Schema], dict[int, Channel], list[Message]]:
        """The raw MCAP schemas and channels by id and the messages in file order (what
        ``repair`` copies)."""
        return self._schemas, self._channels, self._messages

    def _decoder(self, channel: Channel) -> Callable[[bytes], Any]:
        decoder = self._decoders.get(channel.id)
        if decoder is None:
            if channel.message_encoding == "json":
                decoder = json.loads
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


def read_episode(path: str | Path) -> Episode:
    """Read the episode at ``path`` (see the module doc); EpisodeError if it is missing, not
    MCAP, or not an episode."""
    path = Path(path)
    try:
        handle = path.open("rb")
    except OSError as error:
        raise EpisodeError(f"episode '{path}': cannot open: {error.strerror}") from None
    with handle:
        size = path.stat().st_size
        state = _Scan(path)
        reader = StreamReader(handle, emit_chunks=True, validate_crcs=True)
        try:
            for record in reader.records:
                state.take(record)
                state.read_bytes = handle.tell()
        except McapError as error:
            if state.header is None:
                raise EpisodeError(f"episode '{path}': not an MCAP file ({error})") from None
        except (ValueError, EOFError, struct.error) as error:  # a record cut or garbled
            if state.header is None:
                raise EpisodeError(f"episode '{path}': not an MCAP file ({error})") from None
    return state.episode(size)


@dataclass
class _Scan:
    """What one pass over the file's records collects."""

    path: Path
    header: Header | None = None
    finished: bool = False
    read_bytes: int = 0
    metadata: dict[str, dict[str, str]] = field(default_factory=dict)
    attachments: dict[str, bytes] = field(default_factory=dict)
    schemas: dict[int, Schema] = field(default_factory=dict)
    channels: dict[int, Channel] = field(default_factory=dict)
    messages: list[Message] = field(default_factory=list)

    def take(self, record: Any) -> None:
        if isinstance(record, Header):
            if record.profile != PROFILE:
                raise EpisodeError(
                    f"episode '{self.path}': an MCAP file but not an episode "
                    f"(profile {record.profile!r}, expected {PROFILE!r})"
                )
            self.header = record
        elif isinstance(record, Chunk):
            for inner in breakup_chunk(record, validate_crc=True):
                self.take(inner)
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
        elif isinstance(record, Footer):
            self.finished = True

    def episode(self, size: int) -> Episode:
        if self.header is None:
            raise EpisodeError(f"episode '{self.path}': not an MCAP file (no header)")
        version = self.metadata.get(METADATA_EPISODE, {}).get("format_version")
        if version is not None and version.split(".")[0] != FORMAT_VERSION.split(".")[0]:
            raise EpisodeError(
                f"episode '{self.path}': format version {version}, this reader reads "
                f"{FORMAT_VERSION}"
            )
        counts = Counter(self.channels[m.channel_id].topic for m in self.messages)
        return Episode(
            self.path,
            self.metadata,
            self.attachments,
            dict(counts),
            self.finished,
            size if self.finished else self.read_bytes,
            size,
            self.schemas,
            self.channels,
            self.messages,
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
