"""Finishing an episode file left by a killed process, or damaged: ``repair(path, out)``.

The killed file holds every record up to the writer's last flush, but no summary and no
footer, so readers that seek (Foxglove's, Rerun's) may refuse it; a damaged file has byte
ranges no reader can parse. ``repair`` reads every readable record
(controller/episode/reader.py: past damage too), writes them into a new file ``out`` (the
same schemas, channels, messages in order, metadata and attachments, ``application/yaml``
as the writer does), adds the ``repair`` metadata (``complete`` "false", how much of the
source it read, the lost byte ranges) and finishes ``out`` with its summary and footer.
The source is never changed; ``out`` appears only when complete.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from mcap.writer import CompressionType, Writer

from controller.episode.reader import EpisodeError, read_episode
from controller.episode.topics import ATTACHMENT_MEDIA_TYPE, METADATA_REPAIR, PROFILE
from controller.episode.writer import CHUNK_SIZE_BYTES, LIBRARY
from core.atomic_files import atomic_file


@dataclass(frozen=True)
class RepairReport:
    """What ``repair`` did: where the source's readable records end (``read_bytes`` of
    ``source_bytes``), the bytes lost to damage before that (``lost_bytes``) and the
    ``messages`` it copied."""

    source_bytes: int
    read_bytes: int
    messages: int
    lost_bytes: int = 0


def repair(path: str | Path, out: str | Path) -> RepairReport:
    """Write the finished, incomplete-marked copy of the episode ``path`` to ``out`` (see
    the module doc). EpisodeError (one line) if ``path`` cannot be read as an episode, is
    already finished and whole, or ``out`` is ``path`` or exists."""
    path, out = Path(path), Path(out)
    if out.resolve() == path.resolve():
        raise EpisodeError(f"repair: the output '{out}' is the episode itself; name a new file")
    if out.exists():
        raise EpisodeError(f"repair: the output '{out}' exists; name a new file")
    episode = read_episode(path)
    if episode.finished and not episode.damaged:
        raise EpisodeError(f"episode '{path}': already finished and whole, nothing to repair")
    schemas, channels, messages = episode.records()
    with atomic_file(out) as staging, staging.open("wb") as stream:
        writer = Writer(
            stream,
            chunk_size=CHUNK_SIZE_BYTES,
            compression=CompressionType.ZSTD,
            enable_data_crcs=True,
        )
        writer.start(profile=PROFILE, library=LIBRARY)
        schema_ids = {
            old: writer.register_schema(s.name, s.encoding, s.data) for old, s in schemas.items()
        }
        channel_ids = {
            old: writer.register_channel(
                c.topic, c.message_encoding, schema_ids.get(c.schema_id, 0), dict(c.metadata)
            )
            for old, c in channels.items()
        }
        for m in messages:
            writer.add_message(
                channel_ids[m.channel_id], m.log_time, m.data, m.publish_time, m.sequence
            )
        for name, record in episode.metadata.items():
            writer.add_metadata(name, record)
        for name, data in episode.attachments.items():
            media_type = episode.attachment_media.get(name, ATTACHMENT_MEDIA_TYPE)
            writer.add_attachment(0, 0, name, media_type, data)
        report = RepairReport(
            episode.size_bytes, episode.read_bytes, len(messages), episode.lost_bytes
        )
        writer.add_metadata(
            METADATA_REPAIR,
            {
                "complete": "false",
                "source_bytes": str(report.source_bytes),
                "read_bytes": str(report.read_bytes),
                "messages": str(report.messages),
                "lost_bytes": str(report.lost_bytes),
                "lost_ranges": " ".join(f"{r.start}..{r.end}" for r in episode.lost),
            },
        )
        writer.finish()
    return report
