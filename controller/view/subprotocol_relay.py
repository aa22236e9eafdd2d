"""A WebSocket relay that lets a Foxglove client of either protocol name reach the live
stream: ``SubprotocolRelay``.

foxglove-sdk's server (0.30) accepts only the subprotocol ``foxglove.sdk.v1``; Lichtblick
and the Foxglove app of before the SDK offer only ``foxglove.websocket.v1`` and get HTTP
400. The two are the same protocol under two names (Foxglove's stated position; Lichtblick
added the new name beside the old one, lichtblick-suite/lichtblick#819). The relay listens
where the user asked (``websockets``' server, offering both names), and for each client
opens a connection to the SDK's server on the loopback with ``foxglove.sdk.v1`` and copies
every frame, text or binary, both ways unchanged until either side closes.

It runs an asyncio loop on a daemon thread of its own (the episode writer's thread feeds
the SDK server; the loop's thread never waits on either). A failure to listen (a taken
port, a host name that does not resolve, an address not on this machine) is raised by the
constructor as the ``OSError`` it is, for the caller to word.
"""

from __future__ import annotations

import asyncio
import contextlib
import threading
from typing import Any

from websockets.asyncio.client import connect
from websockets.asyncio.server import Server, ServerConnection, serve
from websockets.typing import Subprotocol

SDK_SUBPROTOCOL = Subprotocol("foxglove.sdk.v1")
LEGACY_SUBPROTOCOL = Subprotocol("foxglove.websocket.v1")
START_TIMEOUT_S = 10.0


class SubprotocolRelay:
    """Listen on ``host``:``port`` (0: any free port; ``port`` then says which) and relay
    each client to the Foxglove server at ws://127.0.0.1:``upstream_port``."""

    port: int

    def __init__(self, host: str, port: int, upstream_port: int) -> None:
        self._upstream = f"ws://127.0.0.1:{upstream_port}"
        self._loop = asyncio.new_event_loop()
        self._server: Server | None = None
        self._ready = threading.Event()
        self._error: BaseException | None = None
        self._thread = threading.Thread(
            target=self._run, args=(host, port), name="foxglove-relay", daemon=True
        )
        self._thread.start()
        if not self._ready.wait(START_TIMEOUT_S):
            raise OSError(f"the relay did not start within {START_TIMEOUT_S:g} s")
        if self._error is not None:
            self._thread.join()
            raise self._error
        assert self._server is not None
        self.port = int(self._server.sockets[0].getsockname()[1])

    def _run(self, host: str, port: int) -> None:
        asyncio.set_event_loop(self._loop)
        try:
            self._server = self._loop.run_until_complete(self._listen(host, port))
        except BaseException as error:  # noqa: BLE001 -- handed to the constructor's thread
            self._error = error
            self._ready.set()
            self._loop.close()
            return
        self._ready.set()
        try:
            self._loop.run_until_complete(self._server.wait_closed())
        finally:
            self._loop.close()

    async def _listen(self, host: str, port: int) -> Server:
        return await serve(
            self._relay,
            host,
            port,
            subprotocols=[SDK_SUBPROTOCOL, LEGACY_SUBPROTOCOL],
            max_size=None,
            compression=None,
        )

    async def _relay(self, client: ServerConnection) -> None:
        try:
            async with connect(
                self._upstream, subprotocols=[SDK_SUBPROTOCOL], max_size=None, compression=None
            ) as upstream:
                pumps = [
                    asyncio.ensure_future(_pump(client, upstream)),
                    asyncio.ensure_future(_pump(upstream, client)),
                ]
                _, pending = await asyncio.wait(pumps, return_when=asyncio.FIRST_COMPLETED)
                for task in pending:
                    task.cancel()
        except OSError:  # the stream is closing: the client is let go
            return

    def close(self) -> None:
        """Stop listening and disconnect the clients."""
        if self._server is not None and self._thread.is_alive():
            self._loop.call_soon_threadsafe(self._server.close)
        self._thread.join(START_TIMEOUT_S)


async def _pump(source: Any, sink: Any) -> None:
    """Copy every frame of ``source`` to ``sink`` until either closes."""
    with contextlib.suppress(Exception):  # a closed side ends the copy, whichever it was
        async for frame in source:
            await sink.send(frame)
