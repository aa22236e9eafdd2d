"""How the drivers use xarm-python-sdk: import it quietly, connect with a deadline, and call it
so that Ctrl-C always works.

Facts about the SDK (xarm-python-sdk 1.18, read in its source) that this module works around:

* ``XArmAPI.connect()`` has no timeout. Against a host that accepts the TCP connection and
  never replies, it asks for the firmware version up to 100 times, 2 s each
  (``Base._check_version``): about four minutes. ``connect`` below runs it on a daemon
  thread and waits at most ``timeout_s``; then, or on Ctrl-C, the attempt is abandoned
  (once disconnected it ends within about 10 s: 100 failed requests 0.1 s apart). A new
  ``connect`` of the same ``XArmAPI`` first waits for an abandoned attempt to end, so the
  two never share the object.
* The SDK always connects to TCP port 502 (``XCONF.SocketConf.TCP_CONTROL_PORT``); only the
  address is configurable.
* Every request waits for its reply up to the SDK's command timeout (2 s unless set with
  ``XArmAPI.set_timeout``, which ``connect()`` resets); ``connect`` below sets it to
  ``io_timeout_s`` once connected.
* The reply wait (``Port.read`` in ``xarm/core/comm/base.py``) catches every exception with a
  bare ``except``, so a Ctrl-C that lands while a call waits for its reply is swallowed.
  ``InterruptibleApi`` runs each call made from the main thread on a short-lived daemon
  thread and waits for it interruptibly: Ctrl-C raises KeyboardInterrupt in the caller at
  once, and the call itself ends in the background within its own timeout.
* Importing the SDK prints its version on stdout (``SDK_VERSION: 1.18.4``), and the SDK logs
  to stdout through its own logger (``xarm.core.utils.log.logger``), e.g. a hundred "xArm is
  not connected" lines after an abandoned connect. ``import_sdk`` keeps the banner off the
  terminal (the version is the installed package's, ``importlib.metadata``) and gives that
  logger a ``NullHandler`` in place of its stdout handler: the drivers report every failure
  as a ``DeviceError`` with the SDK's code. An application that wants the SDK's log adds its
  own handler to that logger.
"""

from __future__ import annotations

import functools
import inspect
import io
import logging
import threading
import weakref
from contextlib import redirect_stdout
from typing import Any

from core.errors import DeviceNotConnectedError, DeviceTimeoutError

CONTROL_PORT = 502  # XCONF.SocketConf.TCP_CONTROL_PORT: the only port the SDK connects to

_imported = False
_attempts: weakref.WeakKeyDictionary[Any, threading.Thread] = weakref.WeakKeyDictionary()


def import_sdk() -> None:
    """Import the SDK once: its version banner and its log off the terminal."""
    global _imported
    if _imported:
        return
    with redirect_stdout(io.StringIO()):  # the banner, dropped at the driver's boundary
        import xarm  # noqa: F401  (prints 'SDK_VERSION: ...')
    from xarm.core.utils.log import logger

    for handler in list(logger.handlers):
        logger.removeHandler(handler)
    logger.addHandler(logging.NullHandler())  # no handler at all would mean logging.lastResort
    _imported = True


def new_api(ip: str) -> Any:
    """An ``XArmAPI`` for the controller at ``ip``, in radians, not connected."""
    import_sdk()
    from xarm.wrapper import XArmAPI

    return XArmAPI(ip, is_radian=True, do_not_open=True)


def connect(api: Any, *, ip: str, device: str, timeout_s: float, io_timeout_s: float) -> None:
    """``api.connect()`` within ``timeout_s`` seconds of wall time, then replies bounded by
    ``io_timeout_s`` seconds (``api.set_timeout``). ``api``: an ``XArmAPI`` (not wrapped).

    Raises DeviceNotConnectedError when the SDK gives up (nothing accepts on port 502, or what
    answers is not an xArm controller) and DeviceTimeoutError when it has not finished within
    ``timeout_s``. Ctrl-C raises KeyboardInterrupt at once. After any failure the caller
    should call ``api.disconnect()``; an abandoned attempt that still succeeds later
    disconnects by itself.
    """
    previous = _attempts.get(api)
    if previous is not None:
        previous.join(timeout_s)  # an abandoned attempt still running on this XArmAPI
        if previous.is_alive():
            raise DeviceTimeoutError(
                device,
                f"the previous, abandoned connection attempt to {ip} has not ended after "
                f"{timeout_s} s more; try again in a few seconds",
            )
    abandoned = threading.Event()
    outcome: list[Exception | None] = []

    def attempt() -> None:
        try:
            api.connect()
        except Exception as exc:  # the SDK raises a bare Exception ('connect socket failed')
            outcome.append(exc)
            return
        outcome.append(None)
        if abandoned.is_set():
            api.disconnect()  # connected after the caller gave up

    worker = threading.Thread(target=attempt, name=f"{device}-connect", daemon=True)
    _attempts[api] = worker
    worker.start()
    try:
        worker.join(timeout_s)
    finally:
        if worker.is_alive():
            abandoned.set()
    if worker.is_alive():
        reached = "accepted the connection but" if api.connected else "was not reached and"
        raise DeviceTimeoutError(
            device,
            f"the controller at {ip} (TCP port {CONTROL_PORT}) {reached} did not answer within "
            f"{timeout_s} s (key 'connect_timeout_s'); check that key 'ip' is the xArm control "
            "box (other Modbus TCP devices also listen on port 502) and that it has finished "
            "booting",
        )
    error = outcome[0]
    if error is not None:
        raise DeviceNotConnectedError(
            device,
            f"cannot connect to the controller at {ip} ({error}); check that the control box "
            "is on, the Ethernet link is up and key 'ip' is right",
        ) from error
    api.set_timeout(io_timeout_s)


def call_interruptibly(method: Any, *args: Any, **kwargs: Any) -> Any:
    """``method(*args, **kwargs)``. From the main thread the call runs on a daemon thread while
    the caller waits for it, so that Ctrl-C raises KeyboardInterrupt here at once (the call
    then finishes in the background); from any other thread it runs directly (signals only
    reach the main thread)."""
    if threading.current_thread() is not threading.main_thread():
        return method(*args, **kwargs)
    outcome: dict[str, Any] = {}

    def run() -> None:
        try:
            outcome["value"] = method(*args, **kwargs)
        except BaseException as exc:  # re-raised in the caller
            outcome["error"] = exc

    worker = threading.Thread(target=run, name=f"xarm-{method.__name__}", daemon=True)
    worker.start()
    worker.join()
    if "error" in outcome:
        raise outcome.pop("error")
    return outcome["value"]


class InterruptibleApi:
    """An ``XArmAPI`` (``wrapped``) whose method calls go through ``call_interruptibly``;
    attributes and properties (``connected``, ``mode``, ``state``, ...) read through."""

    def __init__(self, api: Any) -> None:
        self.wrapped = api

    def __getattr__(self, name: str) -> Any:
        value = getattr(self.wrapped, name)
        if inspect.ismethod(value):
            return functools.partial(call_interruptibly, value)
        return value
