"""Checks for driver configuration dataclasses (used in their ``__post_init__``).

Each raises ``ValueError`` naming the field and what was expected, so the YAML loader can
prefix the file name and report e.g. ``configs/robot/xarm6.yaml: key 'servo_rate_hz':
expected a number in [50, 200], got 500``.
"""

from __future__ import annotations

from collections.abc import Collection


def check_range(name: str, value: float, low: float, high: float) -> None:
    """Require ``low <= value <= high`` (and a finite number)."""
    if isinstance(value, bool) or not isinstance(value, int | float) or not low <= value <= high:
        raise ValueError(f"key '{name}': expected a number in [{low}, {high}], got {value!r}")


def check_choice(name: str, value: object, choices: Collection[object]) -> None:
    """Require ``value`` to be one of ``choices``."""
    if value not in choices:
        allowed = ", ".join(repr(c) for c in choices)
        raise ValueError(f"key '{name}': expected one of {allowed}, got {value!r}")


def check_int(name: str, value: object, low: int, high: int) -> None:
    """Require an integer (not a bool) with ``low <= value <= high``."""
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise ValueError(f"key '{name}': expected an integer in [{low}, {high}], got {value!r}")
