"""The episode's streams served live over the Foxglove WebSocket protocol
(``foxglove-sdk``'s ``start_server``), for the Foxglove app's "Open connection".

``FoxgloveLiveStream`` is an ``EpisodeWriter`` listener: each record the writer writes to
the file goes, with the same topic, schema, encoding and bytes, to a channel of the server
(channels open as their topics first appear), on the writer's thread, never the loop's. The
layout docs/foxglove/episode_layout.json therefore works for the live stream as for the file.
The server has its own ``foxglove.Context``, so nothing else in the process logs to it.

The SDK's server listens on the loopback at a free port; clients connect through
``SubprotocolRelay`` (controller/view/subprotocol_relay.py) on the host and port asked for,
so a client offering only the older subprotocol name ``foxglove.websocket.v1`` (Lichtblick,
the Foxglove app before the SDK) is served as one offering ``foxglove.sdk.v1``. ``url``
writes an IPv6 host in brackets (``ws://[::1]:8765``). A failure to listen names the
host and port and says why: a host name that does not resolve, an address this machine
does not have, a port already taken.
"""

from __future__ import annotations

import errno
import socket
from typing import Any

import foxglove

from controller.episode.topics import Topic
from controller.episode.writer import schema_of
from controller.view.subprotocol_relay import SubprotocolRelay

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
                name="tactile-insertion", host="127.0.0.1", port=0, context=self.context
            )
        except Exception as error:  # foxglove-sdk raises its own RuntimeError subclasses
            raise LiveStreamError(
                f"--foxglove: the Foxglove server did not start ({error})"
            ) from None
        try:
            self.relay = SubprotocolRelay(host, port, self.server.port)
        except OSError as error:
            self.server.stop()
            raise LiveStreamError(listen_error(host, port, error)) from None
        self.host = host
        self.port = self.relay.port
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
        return f"ws://{url_host(self.host)}:{self.port}"

    def close(self) -> None:
        """Stop the server (its clients are disconnected)."""
        self.relay.close()
        self.server.stop()


def url_host(host: str) -> str:
    """``host`` as a URL writes it: an IPv6 address in brackets."""
    return f"[{host}]" if ":" in host and not host.startswith("[") else host


def listen_error(host: str, port: int, error: OSError) -> str:
    """One line: where the stream could not listen, and why, with what to change."""
    where = f"--foxglove: cannot listen on {url_host(host)}:{port}"
    if isinstance(error, socket.gaierror):
        reason = error.strerror
        return f"{where}: the host name '{host}' does not resolve ({reason}); check --foxglove-host"
    if error.errno == errno.EADDRINUSE:
        return f"{where}: the port is taken; choose another with --foxglove-port (0: any free port)"
    if error.errno == errno.EADDRNOTAVAIL:
        return f"{where}: this machine has no such address; check --foxglove-host"
    if error.errno == errno.EACCES:
        return (
            f"{where}: permission denied (ports below 1024 need privileges); choose another "
            "--foxglove-port"
        )
    return f"{where}: {error.strerror or error}"
