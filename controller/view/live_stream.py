"""The episode's streams served live over the Foxglove WebSocket protocol
(``foxglove-sdk``'s ``start_server``), for the Foxglove app's "Open connection".

``FoxgloveLiveStream`` is an ``EpisodeWriter`` listener: each record the writer writes to
the file goes, with the same topic, schema, encoding and bytes, to a channel of the server
(channels open as their topics first appear), on the writer's thread, never the loop's. The
layout docs/foxglove/episode_layout.json therefore works for the live stream as for the file.
The server has its own ``foxglove.Context``, so nothing else in the process logs to it.
"""

from __future__ import annotations

from typing import Any

import foxglove

from controller.episode.topics import Topic
from controller.episode.writer import schema_of

DEFAULT_HOST = "127.0.0.1"
DEFAULT_PORT = 8765


class LiveStreamError(OSError):
    """The server could not start (e.g. the port is taken)."""


class FoxgloveLiveStream:
    """A Foxglove WebSocket server on ``host``:``port`` fed by the episode writer (see the
    module doc); LiveStreamError (one line) if it cannot listen there."""

    def __init__(self, host: str = DEFAULT_HOST, port: int = DEFAULT_PORT) -> None:
        self.context = foxglove.Context()
        try:
            self.server = foxglove.start_server(
                name="tactile-insertion", host=host, port=port, context=self.context
            )
        except Exception as error:  # foxglove-sdk raises its own RuntimeError subclasses
            raise LiveStreamError(
                f"--foxglove: cannot listen on {host}:{port} ({error}); is the port taken? "
                "choose another with --foxglove-port"
            ) from None
        self.host = host
        self.port = self.server.port
        self._channels: dict[str, foxglove.Channel] = {}

    def __call__(self, topic: Topic, t_ns: int, payload: Any, data: bytes) -> None:
        del payload
        channel = self._channels.get(topic.name)
        if channel is None:
            name, encoding, schema = schema_of(topic)
            channel = foxglove.Channel(
                topic.name,
                schema=foxglove.Schema(name=name, encoding=encoding, data=schema),
                message_encoding=topic.encoding,
                context=self.context,
            )
            self._channels[topic.name] = channel
        channel.log(data, log_time=t_ns)

    @property
    def url(self) -> str:
        return f"ws://{self.host}:{self.port}"

    def close(self) -> None:
        """Stop the server (its clients are disconnected)."""
        self.server.stop()
