"""Fixtures shared by the driver tests."""

from __future__ import annotations

import pytest

from tests.drivers.silent_controller import SilentController


@pytest.fixture
def silent_controller():
    """A loopback host that accepts on the xArm SDK's port 502 and never answers."""
    host = SilentController()
    try:
        host.__enter__()
    except PermissionError:
        pytest.skip("binding TCP port 502 needs root or CAP_NET_BIND_SERVICE")
    try:
        yield host
    finally:
        host.__exit__()
