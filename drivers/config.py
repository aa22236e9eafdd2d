"""Configuration: YAML files loaded into frozen, validated dataclasses.

Every key must be known and present; a value of the wrong type or out of range is an
error that names the file, the key and what was expected::

    configs/estimators/default.yaml: key 'stride_px': expected a number in [4, 160], got 2

Validation rules live on the dataclass fields as metadata, so each schema is declared once:

* ``meta(low, high)`` -- a number in a closed range;
* ``Literal[...]`` type hints -- a choice;
* nested dataclasses -- sub-mappings, checked recursively;
* ``Mapping[str, X]`` -- a sub-mapping of any string keys to values of type ``X``;
* ``X | None`` -- the key must be present, but may be ``null``.

A dataclass may also check cross-field rules in ``__post_init__`` by raising ``ValueError``
starting with ``key '<name>'``; the loader prefixes the file name and the key path.
"""

from __future__ import annotations

import dataclasses
import types
import typing
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal, TypeVar

import yaml

T = TypeVar("T")

CONFIG_ROOT = Path(__file__).resolve().parent.parent / "configs"


class ConfigError(ValueError):
    """A configuration file is unreadable, or a key is unknown, missing or out of range."""


def meta(low: float, high: float) -> dict[str, Any]:
    """Field metadata declaring the closed range ``[low, high]`` of a numeric key."""
    return {"range": (low, high)}


def number(low: float, high: float) -> Any:
    """A required numeric dataclass field restricted to ``[low, high]``."""
    return field(metadata=meta(low, high))


def load_yaml(path: Path | str) -> dict[str, Any]:
    """Read a YAML mapping; raise ConfigError naming the file if it is missing or malformed."""
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise ConfigError(f"{path}: cannot read configuration file ({exc.strerror})") from None
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise ConfigError(f"{path}: not valid YAML ({exc})") from None
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: expected a mapping of keys at the top level")
    return data


def load_config(cls: type[T], path: Path | str) -> T:
    """Load the YAML file at ``path`` into the dataclass ``cls``, validating every key."""
    return build(cls, load_yaml(path), source=str(path))


def build(cls: type[T], data: Mapping[str, Any], source: str, prefix: str = "") -> T:
    """Build dataclass ``cls`` from ``data``; errors name ``source`` and the dotted key path."""
    if not isinstance(data, Mapping):
        raise ConfigError(f"{source}: key '{prefix.rstrip('.')}': expected a mapping")
    hints = typing.get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls) if f.init}
    unknown = sorted(set(data) - set(fields))
    if unknown:
        raise ConfigError(
            f"{source}: unknown key '{prefix}{unknown[0]}'; expected one of: " + ", ".join(fields)
        )
    kwargs: dict[str, Any] = {}
    for name, f in fields.items():
        key = prefix + name
        if name not in data:
            raise ConfigError(f"{source}: missing key '{key}'")
        kwargs[name] = _convert(hints[name], data[name], f.metadata, source, key)
    try:
        return cls(**kwargs)
    except ValueError as exc:
        raise ConfigError(f"{source}: {_prefixed(str(exc), prefix)}") from None


def _prefixed(message: str, prefix: str) -> str:
    return message.replace("key '", f"key '{prefix}", 1) if prefix else message


def _convert(hint: Any, value: Any, metadata: Mapping[str, Any], source: str, key: str) -> Any:
    origin = typing.get_origin(hint)
    if origin in (typing.Union, types.UnionType):
        options = [a for a in typing.get_args(hint) if a is not type(None)]
        if value is None and len(options) < len(typing.get_args(hint)):
            return None
        return _convert(options[0], value, metadata, source, key)
    if origin is Literal:
        choices = typing.get_args(hint)
        if value not in choices:
            allowed = ", ".join(repr(c) for c in choices)
            raise ConfigError(f"{source}: key '{key}': expected one of {allowed}, got {value!r}")
        return value
    if dataclasses.is_dataclass(hint):
        return build(hint, value, source, prefix=key + ".")
    if origin is Mapping:
        key_type, value_type = typing.get_args(hint)
        if key_type is not str:
            raise TypeError(f"unsupported mapping key type {key_type!r} for key '{key}'")
        if not isinstance(value, Mapping):
            raise ConfigError(f"{source}: key '{key}': expected a mapping, got {value!r}")
        converted = {}
        for name, item in value.items():
            if not isinstance(name, str) or not name:
                raise ConfigError(f"{source}: key '{key}': expected string keys, got {name!r}")
            converted[name] = _convert(value_type, item, {}, source, f"{key}.{name}")
        return converted
    if hint is bool:
        if not isinstance(value, bool):
            raise ConfigError(f"{source}: key '{key}': expected true or false, got {value!r}")
        return value
    if hint in (int, float):
        ok_type = isinstance(value, int) if hint is int else isinstance(value, int | float)
        if isinstance(value, bool) or not ok_type:
            kind = "an integer" if hint is int else "a number"
            raise ConfigError(f"{source}: key '{key}': expected {kind}, got {value!r}")
        low, high = metadata.get("range", (-float("inf"), float("inf")))
        if not low <= value <= high:
            raise ConfigError(
                f"{source}: key '{key}': expected a number in [{low}, {high}], got {value!r}"
            )
        return hint(value)
    if hint is str:
        if not isinstance(value, str) or not value:
            raise ConfigError(f"{source}: key '{key}': expected a non-empty string, got {value!r}")
        return value
    raise TypeError(f"unsupported configuration type {hint!r} for key '{key}'")


@dataclass(frozen=True)
class SensorProfile:
    """Geometry of a visuotactile sensor's working image (after the driver's crop/resize).

    Positions in the sensor frame S are pixels times ``mm_per_px`` from the image centre.
    ``marker_pitch_mm``: printed marker pitch (None: no markers). ``estimator``: the sensor's
    estimator configuration (a name in configs/estimators/ or a YAML path), used whenever a
    caller names none.
    """

    name: str
    width_px: int = number(16, 4096)
    height_px: int = number(16, 4096)
    mm_per_px: float = number(1e-4, 1.0)
    fps_hz: float = number(1, 1000)
    marker_pitch_mm: float | None = number(0.1, 20)
    estimator: str
    description: str


def sensor_profile(name_or_path: str) -> SensorProfile:
    """Load a sensor profile by name (``configs/sensors/NAME.yaml``) or by file path."""
    return load_config(SensorProfile, resolve_config_path(name_or_path, "sensors"))


def resolve_config_path(name_or_path: str, folder: str) -> Path:
    """Path of ``configs/FOLDER/NAME.yaml``, or ``name_or_path`` itself if it is a YAML path."""
    path = Path(name_or_path)
    if path.suffix in (".yaml", ".yml"):
        return path
    candidate = CONFIG_ROOT / folder / f"{name_or_path}.yaml"
    if not candidate.exists():
        known = sorted(p.stem for p in (CONFIG_ROOT / folder).glob("*.yaml"))
        raise ConfigError(
            f"unknown {folder[:-1]} configuration '{name_or_path}'; "
            f"expected one of: {', '.join(known)} (or a path to a .yaml file)"
        )
    return candidate
