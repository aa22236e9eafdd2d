"""Writing an episode file: ``EpisodeWriter``, a logger thread fed by a bounded queue.

The control loop's thread only enqueues (``log``: the topic, the time, an encoder and its
payload appended to a deque; no lock, no encoding, no I/O). The logger thread sleeps until
a flush is due, then encodes every record queued, appends them to the MCAP file
(``foxglove-sdk``'s MCAP writer, in Rust: zstd chunks, compressed on this thread) and flushes
the file (finishing the chunk in progress): one wake-up per flush rather than one per record
(docs/EPISODES.md, "Cost"). A flush is due when ``log`` queues a record ``flush_interval_s``
of log time past the one that made the last due; the loop's observer wakes the thread then,
after queueing its tick (``flush_if_due``: right after the loop's own work, cheaper than a
wake-up on the thread's own timer). It flushes at once when ``flush_soon`` asks (each phase
change), and after ``2 * flush_interval_s`` of wall time without a wake-up (a stalled loop,
a writer fed without the loop's observer). A process killed with SIGKILL therefore leaves
every record up to the last flush readable (controller/episode/reader.py); ``repair``
finishes such a file.

Order: the records are written in the order ``log`` queued them, so the file's order is the
loop's; readers order messages by log time and keep the file's order among messages of equal
log time (the MCAP ``sequence`` this writer gives counts each topic's messages on its own).

When the queue is full the record is dropped, not waited for: the drop is counted by topic,
logged once per topic as a warning, written to ``/episode/drops`` at the next flush and to
the ``outcome`` metadata at the end. A record whose payload its encoder refuses (ValueError,
TypeError: e.g. a value JSON cannot hold) is dropped and counted the same way, and
the writer goes on.

``close(outcome)`` stops the thread after it has written everything queued, writes the
``outcome`` metadata and the file's summary and footer. A failure to write (a full disk)
stops the logger: later records are counted as dropped, and ``close`` raises OSError naming
the file, with the errno of the failed write. The Rust writer writes through ``_Sink``, a
file object of ours that keeps the first OSError (the writer itself reports a failed write
only as a RuntimeError at the next flush, or on stderr when a ``log`` wrote); the logger
checks it after every batch and every flush.
"""

from __future__ import annotations

import errno
import json
import logging
import threading
import time
from collections import Counter, deque
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import IO, Any

import foxglove
import orjson
from foxglove import Channel, Context, Schema
from foxglove.mcap import MCAPCompression, MCAPWriteOptions

from controller.episode.topics import (
    DROPS,
    JSON_SCHEMAS,
    METADATA_EPISODE,
    METADATA_OUTCOME,
    PROFILE,
    Topic,
)

log = logging.getLogger(__name__)

NS_PER_S = 1_000_000_000
QUEUE_SIZE = 4096
"""Records the queue holds (about 8 s of a simulated trial's 520 records a second)."""
FLUSH_INTERVAL_S = 0.07
"""Every 0.07 s of log time: a SIGKILL loses at most this plus the writer's own latency (its
wake-up, writing the records queued since the last flush: about a tick, 0.01 s), within the
0.1 s allowed; each flush costs the logger about 0.25 ms of CPU on this project's machines,
so fewer flushes are the main lever on the writer's share of a core (docs/EPISODES.md
"Cost", docs/BENCHMARKS.md "Episodes")."""
CHUNK_SIZE_BYTES = 4 * 1024 * 1024
"""A chunk is finished at this size or at the next flush, whichever comes first."""
ZSTD_LEVEL = 1
"""The chunks' zstd level: each flush starts a new chunk, and level 1 compresses and
finishes one in about half the CPU of zstd's default 3 (0.46 against 0.84-1.04 ms a flush),
for files about 2% larger (docs/EPISODES.md "Cost")."""
LIBRARY = "tactile-insertion episode writer"
"""The MCAP header's library of a file ``repair`` finishes (the writer's own files name
``foxglove-sdk``'s)."""

Encoder = Callable[[Any], bytes]
"""Turns a payload into a message's bytes (run on the logger thread)."""
Listener = Callable[[Topic, int, Any, bytes], None]
"""Called on the logger thread with each record written: its topic, log time (ns), the
loop's payload and the encoded message (the live view and the Foxglove live stream)."""


def json_bytes(payload: Mapping[str, Any]) -> bytes:
    """A JSON topic's message: ``payload`` as compact JSON (``orjson``: numpy arrays and
    scalars as numbers), without the fields that have no value: a key whose value is None or
    a non-finite number, or a list holding one, is left out (controller/episode/topics.py:
    one JSON type per field, an absent value an absent key). TypeError for a value JSON
    cannot hold.

    The keys whose value is None go before the encoding (most messages have one: a command
    without a pose, a simulated arm without joint angles); only a message still holding a
    null after that (a NaN, or a None in a list) is parsed back and written again."""
    present = {k: v for k, v in payload.items() if v is not None}
    data = orjson.dumps(present, option=orjson.OPT_SERIALIZE_NUMPY)
    if b"null" not in data:  # orjson writes None and NaN as null: nothing else absent
        return data
    kept = {
        k: v
        for k, v in orjson.loads(data).items()
        if v is not None and not (isinstance(v, list) and None in v)
    }
    return orjson.dumps(kept)


def wall_offset_ns(loop_now_s: float) -> int:
    """The offset from the loop's clock (now ``loop_now_s``, s) to the wall clock, integer ns:
    a log time is ``round(t_s * 1e9)`` plus it."""
    return time.time_ns() - round(loop_now_s * NS_PER_S)


class _KeptWriteFailure(logging.Filter):
    """Drops the Rust writer's warning for each message it could not log after a failed write
    (logger ``foxglove.log_sink_set``, "error logging message: McapError(Io(...)": one a
    message, each with the Python traceback of the sink's raise): the sink keeps that OSError
    and the episode's writer reports it once, naming the file."""

    def filter(self, record: logging.LogRecord) -> bool:
        return not record.getMessage().startswith("error logging message: McapError(Io(")


logging.getLogger("foxglove.log_sink_set").addFilter(_KeptWriteFailure())


class _Sink:
    """The episode's file as the Rust MCAP writer writes it: ``stream``'s ``write``, ``seek``
    and ``flush``, keeping the first OSError any of them raised (``error``) before raising it
    on to the writer."""

    def __init__(self, stream: IO[bytes]) -> None:
        self.stream = stream
        self.error: OSError | None = None

    def write(self, data: bytes | bytearray) -> int:
        try:
            return self.stream.write(data)
        except OSError as error:
            self.error = self.error or error
            raise

    def seek(self, offset: int, whence: int = 0) -> int:
        try:
            return self.stream.seek(offset, whence)
        except OSError as error:
            self.error = self.error or error
            raise

    def flush(self) -> None:
        try:
            self.stream.flush()
        except OSError as error:
            self.error = self.error or error
            raise

    def check(self) -> None:
        """Raise the first OSError of a write, seek or flush, if there was one."""
        if self.error is not None:
            raise self.error


def schema_of(topic: Topic) -> tuple[str, str, bytes]:
    """``topic``'s schema as (name, encoding, data): our JSON Schema (``jsonschema``) or
    Foxglove's protobuf FileDescriptorSet."""
    if topic.encoding == "json":
        return topic.schema, "jsonschema", json.dumps(JSON_SCHEMAS[topic.schema]).encode()
    from controller.episode import foxglove_types

    found = foxglove_types.schema(topic.schema)
    return found.name, found.encoding, found.data


class EpisodeWriter:
    """Writes one episode to ``path`` (a new file; FileExistsError if it exists).

    ``info``: the ``episode`` metadata (controller/episode/topics.py, METADATA_EPISODE), to
    which the writer adds ``log_time_offset_ns``; ``loop_now_s``: the loop's clock now (s),
    which fixes the offset from the loop's times to the log times (the wall clock);
    ``attachments``: name -> (media type, bytes), e.g. the task file. ``queue_size``,
    ``flush_interval_s``: see the module doc. ``listeners``: each gets every record written,
    on the logger thread (one that raises is logged and dropped). Use it as a context
    manager, or call ``close``.
    """

    def __init__(
        self,
        path: Path,
        info: Mapping[str, str],
        attachments: Mapping[str, tuple[str, bytes]] = {},
        *,
        queue_size: int = QUEUE_SIZE,
        flush_interval_s: float = FLUSH_INTERVAL_S,
        listeners: Sequence[Listener] = (),
        loop_now_s: float = 0.0,
    ) -> None:
        self.path = Path(path)
        self.offset_ns = wall_offset_ns(loop_now_s)
        """A log time (ns, the wall clock) minus this is the loop's time (ns)."""
        self._listeners = list(listeners)
        self.flush_interval_s = flush_interval_s
        self._stream: IO[bytes] = self.path.open("xb", buffering=0)  # the Rust writer buffers
        self._sink = _Sink(self._stream)
        self._context = Context()  # the channels and this file only: one per episode
        options = MCAPWriteOptions(  # the data section's CRC: damage outside the chunks shows
            compression=MCAPCompression.Zstd,
            compression_level=ZSTD_LEVEL,
            profile=PROFILE,
            chunk_size=CHUNK_SIZE_BYTES,
            calculate_data_section_crc=True,
            compression_threads=0,  # on the logger thread, counted in ``busy_s``
        )
        self._mcap = foxglove.open_mcap(self._sink, context=self._context, writer_options=options)
        self._mcap.write_metadata(
            METADATA_EPISODE, {**dict(info), "log_time_offset_ns": str(self.offset_ns)}
        )
        for name, (media_type, data) in attachments.items():
            self._mcap.attach(log_time=0, create_time=0, name=name, media_type=media_type,
                              data=data)  # fmt: skip
        self._flush()
        self._channels: dict[str, Callable[[bytes, int], None]] = {}
        """Each topic's channel's ``log(data, log_time_ns)`` (``foxglove-sdk``'s own, without
        the ``Channel`` wrapper's checks for the dicts and strings we never pass)."""
        self._queue_size = queue_size
        self._queue: deque[tuple[Topic, int, Encoder, Any]] = deque()
        self.dropped: Counter[str] = Counter()
        self._dropped_written = 0
        self._last_ns = self.offset_ns  # the newest log time written, ns
        self._wake = threading.Event()  # a flush or the stop is wanted now
        self._interval_ns = round(flush_interval_s * NS_PER_S)
        self._due_ns = 0  # the log time from which a record makes a flush due, ns
        self._due = False
        self._stopping = False
        self._error: OSError | None = None
        self._closed = False
        self.busy_s = 0.0
        """CPU time the logger thread has used, s (``time.thread_time``)."""
        self._thread = threading.Thread(target=self._run, name="episode-writer", daemon=True)
        self._thread.start()

    # -- the loop's side (never blocks) ----------------------------------------------------

    def log(self, topic: Topic, t_s: float, encode: Encoder, payload: Any) -> None:
        """Queue one record of ``topic`` logged at ``t_s`` (s on the loop's clock; its log
        time is that plus ``offset_ns``), encoded
        on the logger thread by ``encode(payload)``; dropped and counted if the queue is
        full or the writer has failed. ``payload`` must not change afterwards."""
        if self._error is None and not self._closed and len(self._queue) < self._queue_size:
            t_ns = round(t_s * NS_PER_S) + self.offset_ns
            self._queue.append((topic, t_ns, encode, payload))
            if t_ns >= self._due_ns:  # a flush's worth of log time queued
                self._due_ns = t_ns + self._interval_ns
                self._due = True
            return
        if not self.dropped[topic.name]:
            why = "queue full" if self._error is None and not self._closed else "writer stopped"
            log.warning("episode %s: %s, dropping %s records", self.path, why, topic.name)
        self.dropped[topic.name] += 1

    def flush_if_due(self) -> None:
        """Wake the logger thread if a flush is due (``log`` queued a record
        ``flush_interval_s`` of log time past the one that made the last due): the loop's
        observer calls it once each tick's records are queued, so the logger runs after the
        loop's own work."""
        if self._due:
            self._due = False
            self._wake.set()

    def flush_soon(self) -> None:
        """Ask the logger thread to flush after the records queued so far (a phase change)."""
        self._wake.set()

    @property
    def dropped_total(self) -> int:
        return sum(self.dropped.values())

    # -- the end ---------------------------------------------------------------------------

    def close(self, outcome: Mapping[str, str] | None = None) -> None:
        """Write everything queued, then the ``outcome`` metadata (with the drop counts),
        the summary and the footer; close the file. Idempotent. OSError naming the file if
        writing failed."""
        if self._closed:
            return
        self._closed = True
        self._stopping = True  # the thread writes what is queued, then stops
        self._wake.set()
        self._thread.join()
        try:
            if self._error is None:
                record = {
                    **dict(outcome or {}),
                    "dropped_total": str(self.dropped_total),
                    "dropped_by_topic": json.dumps(dict(self.dropped), sort_keys=True),
                }
                self._write_drops(self._last_ns)
                self._mcap.write_metadata(METADATA_OUTCOME, record)
                self._finish()
        except OSError as error:
            self._error = error
        finally:
            if self._error is not None:
                self._abandon()
            try:
                self._stream.close()
            except OSError as error:
                self._error = self._error or error
        if self._error is not None:
            raise OSError(self._error.errno, self._error.strerror, str(self.path))

    def __enter__(self) -> EpisodeWriter:
        return self

    def __exit__(self, kind: object, error: object, traceback: object) -> None:
        self.close({"error": f"{type(error).__name__}: {error}"} if error else None)

    # -- the logger thread -----------------------------------------------------------------

    def _run(self) -> None:
        began = time.thread_time()
        idle_s = 2.0 * self.flush_interval_s
        try:
            while True:
                self._wake.wait(idle_s)
                self._wake.clear()
                stopping = self._stopping
                written = self._drain()
                if stopping:
                    return
                if written:  # else nothing to flush (a drop needs a full queue)
                    self._write_drops(self._last_ns)
                    self._flush()
        except OSError as error:
            self._error = error
            log.error("episode %s: writing stopped: %s", self.path, error)
        finally:
            self.busy_s = time.thread_time() - began

    def _drain(self) -> int:
        """Write every record queued now (OSError if a write failed); how many there were."""
        queue = self._queue
        pop, write = queue.popleft, self._write
        count = len(queue)
        for _ in range(count):
            write(pop())
        self._sink.check()
        return count

    def _flush(self) -> None:
        """Finish the chunk in progress and flush the file (OSError if that failed)."""
        try:
            self._mcap.flush()
        except RuntimeError as error:  # the Rust writer's failure: the sink has its OSError
            self._raise_failure(error)
        self._sink.check()

    def _finish(self) -> None:
        """Write the summary and the footer (OSError if that failed)."""
        try:
            self._mcap.close()
        except RuntimeError as error:
            self._raise_failure(error)
        self._sink.check()
        self._stream.flush()

    def _abandon(self) -> None:
        """After a failed write: stop the Rust writer, which writes nothing more once a write
        has failed (it would otherwise try to finish the file when collected)."""
        try:
            self._mcap.close()
        except RuntimeError:
            pass  # the failure is ``self._error``

    def _raise_failure(self, error: RuntimeError) -> None:
        self._sink.check()  # the failed write's own OSError, with its errno
        raise OSError(errno.EIO, f"MCAP writer: {error}")

    def _write(self, item: tuple[Topic, int, Encoder, Any]) -> None:
        topic, t_ns, encode, payload = item
        try:
            data = encode(payload)
        except (ValueError, TypeError, OverflowError) as error:  # e.g. a value JSON cannot hold
            if not self.dropped[topic.name]:
                log.error("episode %s: dropping a %s record: %s", self.path, topic.name, error)
            self.dropped[topic.name] += 1
            return
        log_message = self._channels.get(topic.name) or self._register(topic)
        log_message(data, t_ns)
        if t_ns > self._last_ns:
            self._last_ns = t_ns
        if not self._listeners:
            return
        for listener in tuple(self._listeners):
            try:
                listener(topic, t_ns, payload, data)
            except Exception as error:  # a viewer's failure never stops the recording
                log.error("episode %s: listener dropped: %s: %s", self.path,
                          type(error).__name__, error)  # fmt: skip
                self._listeners.remove(listener)

    def _write_drops(self, t_ns: int) -> None:
        total = self.dropped_total
        if total == self._dropped_written:
            return
        self._dropped_written = total
        payload = {"dropped_total": total, "by_topic": dict(self.dropped)}
        self._write((DROPS, t_ns, json_bytes, payload))

    def _register(self, topic: Topic) -> Callable[[bytes, int], None]:
        name, encoding, data = schema_of(topic)
        channel = Channel(
            topic.name,
            schema=Schema(name=name, encoding=encoding, data=data),
            message_encoding=topic.encoding,
            context=self._context,
        )
        log_message = self._channels[topic.name] = channel.base.log
        return log_message
