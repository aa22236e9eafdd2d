"""The text summary of an episode (``replay summary EP``): what run it was, whether the
file is whole, its topics with their counts and rates, its duration, the machine's
transitions with their reasons, the outcome and what the writer dropped."""

from __future__ import annotations

import math
from collections import defaultdict

import numpy as np

from controller.episode import Episode
from controller.episode.topics import LOOP_TICK, METADATA_REPAIR
from controller.replay import episode_streams

RUN_KEYS = ("task", "seed", "controller", "backend", "package_version", "git_revision",
            "tactile_image_format", "jpeg_quality", "started_utc", "machine")  # fmt: skip


def _state(episode: Episode) -> str:
    if episode.unverified_change:
        return f"{_whole_state(episode)}; but the data section's CRC does not match: {CRC_NOTE}"
    return _whole_state(episode)


CRC_NOTE = (
    "a byte outside the chunks changed (metadata or indexes, which MCAP does not check one "
    "by one): the run's metadata may be wrong"
)


def _whole_state(episode: Episode) -> str:
    if episode.complete:
        return "complete"
    if episode.damaged:
        expected = episode.expected_messages
        read = sum(episode.counts.values())
        return (
            f"damaged: {episode.lost_bytes} of {episode.size_bytes} bytes could not be read "
            f"({episode.lost_text()}); {read} messages read"
            + (f" of the {expected} written" if expected else "")
            + ("" if episode.finished else "; no footer (cut short)")
        )
    if episode.finished and METADATA_REPAIR in episode.metadata:
        repair = episode.metadata[METADATA_REPAIR]
        return (
            f"incomplete: repaired from a file cut short or damaged "
            f"({repair.get('read_bytes', '?')} of {repair.get('source_bytes', '?')} bytes read, "
            f"{repair.get('lost_bytes', '0')} bytes lost to damage)"
        )
    if episode.finished:
        return "finished without an outcome"
    return (
        f"truncated: read {episode.read_bytes} of {episode.size_bytes} bytes (up to the last flush)"
    )


def topic_rates(episode: Episode) -> dict[str, float]:
    """Topic -> its mean message rate over its own span, Hz (NaN with one message)."""
    times: dict[str, list[float]] = defaultdict(list)
    for message in episode.messages():
        times[message.topic].append(message.t_s)
    rates = {}
    for topic, values in times.items():
        span = values[-1] - values[0]
        rates[topic] = (len(values) - 1) / span if span > 0 else math.nan
    return rates


def _drops(episode: Episode) -> str:
    total, by_topic = episode_streams.drops(episode)
    detail = ", ".join(f"{topic} {count}" for topic, count in sorted(by_topic.items()))
    cut = " (until the cut)" if episode.outcome is None else ""
    return f"{total} records" + (f" ({detail})" if detail else "") + cut


def summary_lines(episode: Episode) -> list[str]:
    """The summary, line by line."""
    info = episode.info
    start, end = episode.time_range_s()
    lines = [f"episode: {episode.path}", f"file: {_state(episode)}"]
    lines += [f"{key}: {info[key]}" for key in RUN_KEYS if key in info]
    if np.isfinite(start):
        lines.append(f"duration: {end - start:.3f} s (loop clock {start:.3f} .. {end:.3f} s)")
    else:
        lines.append("duration: none: no messages (the run ended before its first tick)")
    if not episode.counts.get(LOOP_TICK.name):
        lines.append(f"ticks: none ({LOOP_TICK.name}: the run ended before its first tick)")
    rates = topic_rates(episode)
    lines.append("topics:")
    width = max((len(topic) for topic in episode.topics), default=0)
    for topic in episode.topics:
        rate = rates.get(topic, math.nan)
        shown = f"{rate:8.2f} Hz" if np.isfinite(rate) else "       - Hz"
        lines.append(f"  {topic:<{width}}  {episode.counts[topic]:7d}  {shown}")
    changes = episode_streams.transitions(episode)
    lines.append(f"transitions: {len(changes)}")
    lines += [
        f"  {c.t_s:8.3f} s  {c.source} -> {c.target}: {c.reason}"
        + (f" ({c.rule})" if c.rule else "")
        for c in changes
    ]
    outcome = episode.outcome
    if outcome is None:
        lines.append("outcome: none written (the run did not finish the file)")
    else:
        ended = outcome.get("reason", "?")
        message = outcome.get("message", "")
        lines.append(
            f"outcome: {ended}" + (f" ({message})" if message and message != ended else "")
        )
        if outcome.get("error"):
            lines.append(f"error: {outcome['error']}")
    lines.append(f"dropped: {_drops(episode)}")
    return lines
