"""The readable records of an MCAP file that may be cut short or damaged: ``scan_records``.

MCAP's ``StreamReader`` reads front to back and stops at the first record it cannot read.
``scan_records`` reads every record it can, one at a time (each parsed by ``mcap`` itself),
and reads on past damage:

* a chunk whose framing is intact but whose compressed bytes or CRC are wrong is skipped
  whole: its byte range is lost, the records after it are read;
* a record whose framing is broken (an unknown opcode, a length running past the file's
  end, bytes ``mcap`` cannot parse) stops the sequence there; the scan looks for the next
  offset where the records read whole again (a record found only outside chunks: a chunk
  whose CRC matches, or one followed by a second record that reads; the footer only in its
  place before the closing magic) and reads on from there.
  The bytes between are lost;
* the file's end inside a record, with nothing readable after it (a killed writer's last
  flush), is a cut, not a loss: ``read_bytes`` ends at the last whole record;
* a byte changed outside the chunks (metadata, message indexes: MCAP gives them no CRC of
  their own) parses as it stands; the data section's CRC (its ``DataEnd`` record) then
  differs from the bytes', and ``data_crc_matches`` says so (None when there is no
  ``DataEnd`` or no CRC in it).

Offsets are bytes from the file's start; a range is ``[start, end)``.
"""

from __future__ import annotations

import io
import mmap
import re
import zlib
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from mcap.opcode import Opcode
from mcap.records import Chunk, DataEnd, Footer, Header
from mcap.stream_reader import MAGIC_SIZE, StreamReader, breakup_chunk
from mcap.writer import MCAP0_MAGIC

RECORD_PREFIX = 9
"""An MCAP record's opcode (1 byte) and length (8 bytes, little-endian)."""
FOOTER_RECORD = RECORD_PREFIX + 20
KNOWN_OPCODES = frozenset(int(op) for op in Opcode)
_CANDIDATE = re.compile(rb"[\x02\x06-\x0f][\x00-\xff]{5}\x00\x00\x00", re.DOTALL)
"""Where reading may resume: the opcode of a record found only outside chunks (not a
schema, channel or message, which an uncompressed chunk holds as plain records) and a
length below 2**40 bytes (random bytes pass this test about once in 400 million offsets)."""


class NotMcap(ValueError):
    """The file does not start with an MCAP magic and header (one line, no file name)."""


@dataclass(frozen=True)
class LostRange:
    """Bytes ``[start, end)`` of the file that held no readable record, and why."""

    start: int
    end: int
    reason: str

    @property
    def size(self) -> int:
        return self.end - self.start


@dataclass
class ScanResult:
    """What ``scan_records`` found: the ``header``, whether the ``footer`` was read, the
    ``lost`` byte ranges in file order, ``read_bytes``: where the readable records end
    (the file's size unless it is cut short), and ``data_crc_matches``: whether the data
    section's CRC matches its bytes (None: not recorded)."""

    header: Header
    finished: bool
    read_bytes: int
    lost: list[LostRange] = field(default_factory=list)
    data_crc_matches: bool | None = None


class _Broken(Exception):
    """A record that cannot be read at an offset; ``cut``: it runs past the file's end."""

    def __init__(self, reason: str, cut: bool = False) -> None:
        super().__init__(reason)
        self.cut = cut


def scan_records(handle: io.BufferedReader, take: Callable[[Any], None]) -> ScanResult:
    """Read the open MCAP file ``handle``, calling ``take`` with each record it can read in
    file order (a chunk's schemas, channels and messages in its place, all or none of
    them); see the module doc. NotMcap if the file has no MCAP magic or no readable header
    at its start; what ``take`` raises propagates."""
    size = _file_size(handle)
    if size < MAGIC_SIZE or handle.read(MAGIC_SIZE) != MCAP0_MAGIC:
        raise NotMcap("no MCAP magic at its start")
    if size == MAGIC_SIZE:
        raise NotMcap("nothing after its magic (no header)")
    with mmap.mmap(handle.fileno(), 0, access=mmap.ACCESS_READ) as data:
        try:
            header, pos = _record_at(data, MAGIC_SIZE)
        except _Broken as error:
            raise NotMcap(f"no readable header ({error})") from None
        if not isinstance(header, Header):
            raise NotMcap(f"its first record is a {type(header).__name__}, not a header")
        take(header)
        result = ScanResult(header, False, size)
        while pos < size:
            try:
                record, end = _record_at(data, pos)
            except _Broken as error:
                resume = _next_readable(data, pos + 1)
                if resume is None and error.cut:
                    result.read_bytes = pos
                    return result
                resume = size if resume is None else resume
                _lose(result.lost, LostRange(pos, resume, str(error)))
                pos = resume
                continue
            if isinstance(record, Chunk):
                try:
                    inner = breakup_chunk(record, validate_crc=True)
                except Exception as error:  # noqa: BLE001 -- any failure of damaged bytes
                    _lose(result.lost, LostRange(pos, end, f"a chunk that {_what(error)}"))
                    pos = end
                    continue
                for item in inner:
                    take(item)
            else:
                take(record)
            if isinstance(record, DataEnd) and record.data_section_crc != 0:
                result.data_crc_matches = zlib.crc32(data[:pos]) == record.data_section_crc
            pos = end
            if isinstance(record, Footer):
                result.finished = True
                return result
        result.read_bytes = pos
        return result


def _lose(lost: list[LostRange], new: LostRange) -> None:
    """Append ``new`` to ``lost``, joined to the last range when they touch (one damaged
    stretch, described by its first reason)."""
    if lost and lost[-1].end == new.start:
        lost[-1] = LostRange(lost[-1].start, new.end, lost[-1].reason)
    else:
        lost.append(new)


def _file_size(handle: io.BufferedReader) -> int:
    handle.seek(0, io.SEEK_END)
    size = handle.tell()
    handle.seek(0)
    return size


def _what(error: Exception) -> str:
    text = " ".join(str(error).split()) or type(error).__name__
    return f"does not decompress or fails its CRC ({text[:120]})"


def _record_at(data: mmap.mmap, pos: int) -> tuple[Any, int]:
    """The record starting at ``pos`` and the offset after it; _Broken if there is none."""
    size = len(data)
    if pos + RECORD_PREFIX > size:
        raise _Broken("the file ends inside a record's opcode and length", cut=True)
    opcode = data[pos]
    length = int.from_bytes(data[pos + 1 : pos + RECORD_PREFIX], "little")
    if opcode not in KNOWN_OPCODES:
        raise _Broken(f"no record: unknown opcode 0x{opcode:02x}")
    end = pos + RECORD_PREFIX + length
    if end > size:
        raise _Broken(
            f"a record (opcode 0x{opcode:02x}) of {length} bytes runs past the file's end",
            cut=True,
        )
    reader = StreamReader(io.BytesIO(data[pos:end]), skip_magic=True, emit_chunks=True)
    try:
        record = next(iter(reader.records))
    except Exception as error:  # noqa: BLE001 -- garbage bytes fail in many ways
        raise _Broken(f"a record (opcode 0x{opcode:02x}) that does not parse: {error}") from None
    return record, end


def _next_readable(data: mmap.mmap, start: int) -> int | None:
    """The first offset at or after ``start`` where records read whole again (see the
    module doc), None if there is none."""
    for match in _CANDIDATE.finditer(data, start):
        if _reads_whole(data, match.start()):
            return match.start()
    return None


def _reads_whole(data: mmap.mmap, pos: int) -> bool:
    size = len(data)
    try:
        record, end = _record_at(data, pos)
        if isinstance(record, Footer):
            return end == size - MAGIC_SIZE and data[end:] == MCAP0_MAGIC
        if isinstance(record, Chunk):
            breakup_chunk(record, validate_crc=True)
            if record.uncompressed_crc != 0:
                return True
        if end == size:
            return False
        _record_at(data, end)
    except Exception:  # noqa: BLE001 -- not a record boundary
        return False
    return True
