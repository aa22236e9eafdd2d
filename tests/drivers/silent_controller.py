"""A host that accepts TCP connections on the xArm's ports and never sends a byte.

The xArm SDK always connects to port 502 (and its report port 30002), so the listener binds
those ports on a loopback address of its own, ``127.x.y.z`` chosen at random: Linux routes
all of 127.0.0.0/8 to the loopback interface, and other processes' tests on 127.0.0.1:502
are left alone. Binding port 502 needs root or CAP_NET_BIND_SERVICE; ``SilentController``
raises PermissionError otherwise (tests skip on it).
"""

from __future__ import annotations

import random
import socket
import threading

PORTS = (502, 30002)  # XCONF.SocketConf.TCP_CONTROL_PORT, TCP_REPORT_RICH_PORT


class SilentController:
    """``with SilentController() as host:`` -- ``host.ip`` accepts and stays silent;
    ``host.accepted`` is set once a client connected to port 502."""

    def __init__(self) -> None:
        self.ip = f"127.{random.randint(1, 254)}.{random.randint(1, 254)}.{random.randint(2, 254)}"
        self.accepted = threading.Event()
        self._listeners: list[socket.socket] = []
        self._clients: list[socket.socket] = []
        self._threads: list[threading.Thread] = []

    def __enter__(self) -> SilentController:
        try:
            for port in PORTS:
                listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
                listener.settimeout(None)  # the SDK sets a 1 s default for new sockets
                self._listeners.append(listener)
                listener.bind((self.ip, port))
                listener.listen()
        except BaseException:
            self.__exit__()
            raise
        for listener, port in zip(self._listeners, PORTS, strict=True):
            thread = threading.Thread(target=self._accept, args=(listener, port), daemon=True)
            thread.start()
            self._threads.append(thread)
        return self

    def __exit__(self, *exc_info: object) -> None:
        for sock in self._listeners + self._clients:
            try:
                sock.shutdown(socket.SHUT_RDWR)
            except OSError:
                pass
            sock.close()
        for thread in self._threads:
            thread.join(2.0)

    def _accept(self, listener: socket.socket, port: int) -> None:
        while True:
            try:
                client, _ = listener.accept()
            except OSError:  # closed by __exit__
                return
            self._clients.append(client)  # kept open, never written to
            if port == PORTS[0]:
                self.accepted.set()
