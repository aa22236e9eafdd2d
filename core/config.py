"""Configuration: YAML files loaded into frozen dataclasses that validate themselves.

One mechanism serves the controller, the drivers and evaluation (it lives in ``core``, below
every layer). A configuration class derives from ``Config``, is decorated with
``@config_dataclass`` (a frozen dataclass; ``@config_dataclass(kw_only=True)`` for keyword-only
fields) and declares each key once, on its dataclass field:

* ``float``/``int`` annotations with ``number(low, high)`` -- a finite number (an integer
  for ``int``) in the closed range ``[low, high]``; a bool is never a number;
* ``Literal[...]`` -- a choice; ``bool`` -- true or false; ``str`` -- a non-empty string;
* a nested ``Config`` class -- a sub-mapping, checked recursively;
* ``Mapping[str, X]`` -- a sub-mapping of any string keys to ``X`` (stored read-only);
* ``tuple[X, X, X]`` -- a fixed-length sequence (a YAML list);
* ``X | None`` -- the key may be ``null``.

The declarations are checked whenever an instance is made, by ``build`` from YAML or
directly in code (``HandEConfig(timeout_s=9)`` raises ``ValueError: key 'timeout_s':
expected a number in [0.005, 5.0], got 9``). Cross-field rules go in ``__post_init__``,
which runs after the field checks, and raise ``ValueError`` starting with ``key '<name>'``.

Loading from YAML adds the file: every key must be known and present (defaults serve code,
not files), and an error names the file, the dotted key path and what was expected::

    configs/estimators/default.yaml: key 'stride_px': expected a number in [4, 160], got 2

Command-line overrides (``--set scene.friction=0.5``) go through ``apply_overrides`` on the
raw mapping before ``build``, so an overridden value is validated exactly as one from YAML.

**Safety rules are not settings.** A ``Config`` class names, in its ``safety_rules``, the
keys that once switched a safety rule and no longer exist, each with the rule it keeps
(``TeleopConfig``: the deadman). A file or an override that sets one is refused in one line
that states the rule, rather than as an unknown key: no setting can loosen a safety rule.

``config_dataclass`` is ``dataclasses.dataclass(frozen=True)`` at run time. It is declared a
PEP 681 dataclass transform with ``number`` as a field specifier, so the type checker (mypy,
``make typecheck``) knows that ``number(low, high)`` declares a required key and
``number(low, high, default=d)`` an optional one; a plain ``@dataclass`` would take every
``number`` field for one with a default.
"""

from __future__ import annotations

import copy
import copyreg
import dataclasses
import functools
import importlib.resources
import math
import numbers
import re
import types
import typing
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any, ClassVar, Literal, TypeVar

import yaml

T = TypeVar("T")

CONFIG_ROOT = Path(str(importlib.resources.files("configs")))
"""The shipped configurations: the ``configs`` package's folder (package data, found through
``importlib.resources`` in a checkout and in an installed wheel alike)."""
_RANGE = "range"
_SHOWN_CHARS = 80  # longest value repr quoted in a message


class ConfigError(ValueError):
    """A configuration file is unreadable, or a key is unknown, missing or out of range.

    The message is always one line: line breaks inside it (a key or value quoted from the
    file) are shown escaped."""

    def __init__(self, message: str) -> None:
        super().__init__(str(message).replace("\r", "\\r").replace("\n", "\\n"))


@typing.overload
def number(low: float, high: float) -> Any: ...


@typing.overload
def number(low: float, high: float, *, default: T) -> T: ...


def number(low: float, high: float, *, default: Any = dataclasses.MISSING) -> Any:
    """A numeric dataclass field restricted to ``[low, high]`` (an integer if annotated
    ``int``); ``default`` serves construction in code (a YAML file must give every key).
    The overloads tell a type checker which fields have a default (``config_dataclass``)."""
    return dataclasses.field(default=default, metadata={_RANGE: (low, high)})


@typing.overload
def config_dataclass(cls: type[T], /) -> type[T]: ...


@typing.overload
def config_dataclass(*, kw_only: bool = False) -> Callable[[type[T]], type[T]]: ...


@typing.dataclass_transform(frozen_default=True, field_specifiers=(dataclasses.field, number))
def config_dataclass(cls: type[T] | None = None, /, *, kw_only: bool = False) -> Any:
    """The decorator of every ``Config`` class: ``dataclasses.dataclass(frozen=True)``
    (``@config_dataclass``, or ``@config_dataclass(kw_only=True)`` for keyword-only fields),
    which type checkers see as a dataclass transform with ``number`` fields (module doc)."""

    def decorate(cls: type[T]) -> type[T]:
        return dataclasses.dataclass(frozen=True, kw_only=kw_only)(cls)

    return decorate if cls is None else decorate(cls)


class Config:
    """Base of every configuration dataclass: construction checks the declared fields.

    Subclasses are ``@config_dataclass``; a subclass's own ``__post_init__`` (its
    cross-field rules) runs after the checks of every field, which run once per instance.
    Values are normalised on the way: an int given for a ``float`` becomes a float, a list
    for a tuple a tuple, a mapping a read-only mapping.
    """

    safety_rules: ClassVar[Mapping[str, str]] = {}
    """Keys that no file or override may set (module doc), each with the rule it keeps."""

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        rules = cls.__dict__.get("__post_init__")

        def __post_init__(self: Config) -> None:
            if type(self) is cls:
                _check_fields(self)
            if rules is not None:
                rules(self)
            else:  # the rules after cls's in self's MRO (mypy would look after Config's)
                following: Any = super(cls, self)
                following.__post_init__()

        cls.__post_init__ = __post_init__  # type: ignore[method-assign]  # wrapping is the point

    def __post_init__(self) -> None:
        """The end of the chain: no rules of its own."""


def check_number(
    key: str, value: Any, low: float = -math.inf, high: float = math.inf, integer: bool = False
) -> Any:
    """``value`` as a float (an int with ``integer``) if it is a finite number in
    ``[low, high]``; otherwise ValueError ``key '<key>': expected a number in [low, high]``.
    The check behind every ``number`` field, for ranges known only at run time."""
    kind = numbers.Integral if integer else numbers.Real
    convert: Callable[[Any], float] = int if integer else float
    converted: float | None = None
    if isinstance(value, kind) and not isinstance(value, bool):
        try:
            converted = convert(value)
        except OverflowError:
            converted = None
    if converted is None or not math.isfinite(converted) or not low <= converted <= high:
        bounded = math.isfinite(low) or math.isfinite(high)
        what = "an integer" if integer else "a number" if bounded else "a finite number"
        where = f" in [{low}, {high}]" if bounded else ""
        raise ValueError(f"key '{key}': expected {what}{where}, got {show(value)}")
    return converted


def show(value: Any) -> str:
    """``repr(value)`` cut to a readable length, for one-line messages."""
    text = repr(value)
    return text if len(text) <= _SHOWN_CHARS else text[: _SHOWN_CHARS - 3] + "..."


@functools.cache
def _field_specs(cls: type) -> tuple[tuple[str, Any, tuple[float, float] | None], ...]:
    hints = typing.get_type_hints(cls)
    return tuple(
        (f.name, hints[f.name], f.metadata.get(_RANGE)) for f in dataclasses.fields(cls) if f.init
    )


def _check_fields(config: Config) -> None:
    specs = _field_specs(type(config))  # type: ignore[arg-type]  # a class is Hashable, mypy#11470
    for name, hint, bounds in specs:
        value = getattr(config, name)
        checked = _check(hint, value, name, bounds)
        if checked is not value:
            object.__setattr__(config, name, checked)


def _check(hint: Any, value: Any, key: str, bounds: tuple[float, float] | None) -> Any:
    """``value`` checked against the type ``hint`` (and ``bounds`` for its numbers),
    normalised; ValueError naming ``key`` otherwise."""
    origin = typing.get_origin(hint)
    if origin in (typing.Union, types.UnionType):
        options = _optional_of(hint, key)
        return None if value is None else _check(options, value, key, bounds)
    if origin is Literal:
        for choice in typing.get_args(hint):
            if _kind(value) is _kind(choice) and value == choice:
                return choice
        allowed = ", ".join(repr(c) for c in typing.get_args(hint))
        raise ValueError(f"key '{key}': expected one of {allowed}, got {show(value)}")
    if hint is bool:
        if not isinstance(value, bool):
            raise ValueError(f"key '{key}': expected true or false, got {show(value)}")
        return value
    if hint in (int, float):
        low, high = bounds if bounds is not None else (-math.inf, math.inf)
        return check_number(key, value, low, high, integer=hint is int)
    if hint is str:
        if not isinstance(value, str) or not value:
            raise ValueError(f"key '{key}': expected a non-empty string, got {show(value)}")
        return value
    if isinstance(hint, type) and issubclass(hint, Config):
        if not isinstance(value, hint):
            raise ValueError(f"key '{key}': expected a {hint.__name__}, got {show(value)}")
        return value
    if origin is Mapping:
        return _check_mapping(hint, value, key, bounds)
    if origin is tuple:
        return _check_tuple(hint, value, key, bounds)
    raise TypeError(f"unsupported configuration type {hint!r} for key '{key}'")


def _check_mapping(hint: Any, value: Any, key: str, bounds: tuple[float, float] | None) -> Any:
    key_type, value_type = typing.get_args(hint)
    if key_type is not str:
        raise TypeError(f"unsupported mapping key type {key_type!r} for key '{key}'")
    if not isinstance(value, Mapping):
        raise ValueError(f"key '{key}': expected a mapping, got {show(value)}")
    checked = {}
    for name, item in value.items():
        if not isinstance(name, str) or not name:
            raise ValueError(f"key '{key}': expected string keys, got {show(name)}")
        checked[name] = _check(value_type, item, f"{key}.{name}", bounds)
    return types.MappingProxyType(checked)


def _read_only(mapping: dict) -> types.MappingProxyType:
    return types.MappingProxyType(mapping)


def _pickle_mapping_proxy(proxy: types.MappingProxyType) -> tuple:
    return _read_only, (dict(proxy),)


# A checked mapping is read-only (MappingProxyType); this lets a configuration holding one
# cross to a worker process and back (multiprocessing pickles it).
copyreg.pickle(types.MappingProxyType, _pickle_mapping_proxy)


def _check_tuple(hint: Any, value: Any, key: str, bounds: tuple[float, float] | None) -> Any:
    item_types = typing.get_args(hint)
    if not isinstance(value, tuple | list) or len(value) != len(item_types):
        raise ValueError(f"key '{key}': expected {len(item_types)} items, got {show(value)}")
    return tuple(
        _check(t, v, f"{key}[{i}]", bounds)
        for i, (t, v) in enumerate(zip(item_types, value, strict=True))
    )


def _optional_of(hint: Any, key: str) -> Any:
    options = [a for a in typing.get_args(hint) if a is not type(None)]
    if len(options) != 1 or len(typing.get_args(hint)) != 2:
        raise TypeError(f"unsupported configuration type {hint!r} for key '{key}'")
    return options[0]


def _kind(value: Any) -> type:
    """bool, int, float or the value's own type: a choice matches only its own kind."""
    if isinstance(value, bool):
        return bool
    if isinstance(value, numbers.Integral):
        return int
    if isinstance(value, numbers.Real):
        return float
    return type(value)


# -- YAML ----------------------------------------------------------------------------


class _StrictLoader(yaml.SafeLoader):
    """PyYAML's safe loader, refusing a key given twice in one mapping, and reading a number
    with an exponent as a float (YAML 1.2) even without a dot or the exponent's sign
    (``5e-1``, ``1E3``, ``1.5e3``), which PyYAML's YAML 1.1 pattern leaves as text."""

    def construct_mapping(self, node: Any, deep: bool = False) -> Any:
        if isinstance(node, yaml.MappingNode):
            seen: set[Any] = set()
            for key_node, _ in node.value:
                if key_node.tag == "tag:yaml.org,2002:merge":
                    continue  # merged keys may be overridden: that is what a merge is for
                key = self.construct_object(key_node, deep=True)
                if not isinstance(key, typing.Hashable):
                    continue  # PyYAML reports it
                if key in seen:
                    raise yaml.constructor.ConstructorError(
                        None, None, f"key {show(key)} given twice", key_node.start_mark
                    )
                seen.add(key)
        return super().construct_mapping(node, deep=deep)


_StrictLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9][0-9_]*)[eE][-+]?[0-9]+$"),
    list("-+.0123456789"),
)


_YAML_ERRORS = (yaml.YAMLError, ValueError, TypeError, AttributeError, RecursionError)
"""What reading YAML text may raise: PyYAML's constructors raise plain Python errors on a few
malformed scalars (the timestamp 2020-13-45, a tagged !!float x, an integer of more digits
than Python converts), and deep nesting exhausts the recursion limit."""


MAX_CONFIG_BYTES = 16 * 2**20
"""The largest configuration file read: a device or stream that never ends (/dev/zero,
/dev/full) is refused after this many bytes instead of filling the memory."""


def load_yaml(path: Path | str) -> dict[str, Any]:
    """The top-level mapping of the YAML file at ``path``; ConfigError naming the file if it
    is missing, larger than ``MAX_CONFIG_BYTES``, not UTF-8 text, not valid YAML (with line
    and column), empty or not a mapping."""
    path = Path(path)
    try:
        with path.open("rb") as stream:
            raw = stream.read(MAX_CONFIG_BYTES + 1)
    except OSError as exc:
        reason = exc.strerror or type(exc).__name__
        raise ConfigError(f"{path}: cannot read configuration file ({reason})") from None
    if len(raw) > MAX_CONFIG_BYTES:
        raise ConfigError(
            f"{path}: more than {MAX_CONFIG_BYTES // 2**20} MiB; expected a configuration file"
        )
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigError(
            f"{path}: not a UTF-8 text file (byte 0x{raw[exc.start]:02x} at offset {exc.start})"
        ) from None
    try:
        data = copy.deepcopy(_parsed(text))  # the caller's own copy: it may change it
    except yaml.MarkedYAMLError as exc:
        raise ConfigError(_yaml_message(path, exc)) from None
    except yaml.reader.ReaderError as exc:
        line, column = _line_column(text, exc.position)
        char = exc.character
        code = f"#x{char:04x}" if isinstance(char, int) else show(char)
        raise ConfigError(
            f"{path}: line {line}, column {column}: not valid YAML: "
            f"unacceptable character {code} ({exc.reason})"
        ) from None
    except _YAML_ERRORS as exc:
        raise ConfigError(f"{path}: not valid YAML ({_one_line(str(exc))})") from None
    if data is None:
        raise ConfigError(f"{path}: empty configuration file; expected a mapping of keys")
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: expected a mapping of keys at the top level, got {show(data)}")
    return data


@functools.lru_cache(maxsize=64)
def _parsed(text: str) -> Any:
    """The YAML ``text`` read by the strict SafeLoader, kept for the next read of the same
    text (a process loads the same configuration files again and again; the parse is pure
    Python). An error is raised each time, never kept."""
    return yaml.load(text, Loader=_StrictLoader)


BASE_KEY = "extends"
"""The key by which a file builds on a base file (``load_yaml_extending``)."""


def load_yaml_extending(path: Path | str) -> dict[str, Any]:
    """The top-level mapping of the YAML file at ``path``, laid over its base file.

    A file whose top level has ``extends: BASE.yaml`` (a path relative to the file's folder,
    or absolute) holds only what differs from BASE: the base is loaded (itself possibly
    extending another), then the file's keys are laid over it, mapping into mapping key by
    key, any other value (a number, a string, a list) replacing the base's whole. The
    ``extends`` key itself is dropped. ConfigError naming the file and the key for a missing
    base, a base that is not a path, or a cycle; every other check is the caller's ``build``
    on the merged mapping, as for a single file."""
    return _load_extending(Path(path), ())


def _load_extending(path: Path, chain: tuple[Path, ...]) -> dict[str, Any]:
    data = load_yaml(path)
    if BASE_KEY not in data:
        return data
    base_name = data.pop(BASE_KEY)
    if not isinstance(base_name, str) or not base_name.endswith((".yaml", ".yml")):
        raise ConfigError(
            f"{path}: key '{BASE_KEY}': expected the path of a base .yaml file, "
            f"got {show(base_name)}"
        )
    base_path = (path.parent / base_name).resolve()
    if base_path in chain or base_path == path.resolve():
        raise ConfigError(f"{path}: key '{BASE_KEY}': {base_name} extends this file (a cycle)")
    if not base_path.is_file():
        raise ConfigError(f"{path}: key '{BASE_KEY}': no such base file {base_path}")
    return _laid_over(_load_extending(base_path, (*chain, path.resolve())), data)


def _laid_over(base: dict[str, Any], top: Mapping[str, Any]) -> dict[str, Any]:
    merged = dict(base)
    for key, value in top.items():
        below = merged.get(key)
        if isinstance(value, dict) and isinstance(below, dict):
            merged[key] = _laid_over(below, value)
        else:
            merged[key] = value
    return merged


def _yaml_message(path: Path, exc: yaml.MarkedYAMLError) -> str:
    mark = exc.problem_mark or exc.context_mark
    where = f" line {mark.line + 1}, column {mark.column + 1}:" if mark is not None else ""
    what = exc.problem or exc.context or "parse error"
    return f"{path}:{where} not valid YAML: {_one_line(what)}"


def _line_column(text: str, position: int) -> tuple[int, int]:
    line = text.count("\n", 0, position) + 1
    return line, position - (text.rfind("\n", 0, position) + 1) + 1


def _one_line(message: str) -> str:
    return " ".join(message.split())


def load_config(cls: type[T], path: Path | str) -> T:
    """Load the YAML file at ``path`` into the ``Config`` class ``cls``, checking every key."""
    return build(cls, load_yaml(path), source=str(path))


def build(cls: type[T], data: Mapping[str, Any], source: str, prefix: str = "") -> T:
    """Build the ``Config`` class ``cls`` from ``data``; errors are ConfigErrors naming
    ``source`` and the dotted key path (``prefix`` is the path of ``data`` itself)."""
    if not (isinstance(cls, type) and issubclass(cls, Config) and dataclasses.is_dataclass(cls)):
        raise TypeError(f"{cls!r} is not a Config dataclass")
    if not isinstance(data, Mapping):
        where = f"key '{prefix.rstrip('.')}': " if prefix else ""
        raise ConfigError(f"{source}: {where}expected a mapping, got {show(data)}")
    hints = typing.get_type_hints(cls)
    fields = [f.name for f in dataclasses.fields(cls) if f.init]
    for key in data:
        if key in cls.safety_rules:
            where = f"key '{prefix}{key}'"
            raise ConfigError(safety_rule_message(source, where, cls.safety_rules[key]))
    unknown = sorted((key for key in data if key not in fields), key=str)
    if unknown:
        raise ConfigError(
            f"{source}: unknown key '{prefix}{unknown[0]}'; expected one of: " + ", ".join(fields)
        )
    kwargs: dict[str, Any] = {}
    for name in fields:
        if name not in data:
            raise ConfigError(f"{source}: missing key '{prefix}{name}'")
        kwargs[name] = _from_yaml(hints[name], data[name], source, prefix + name)
    try:
        return cls(**kwargs)
    except ConfigError:
        raise
    except ValueError as exc:
        raise ConfigError(f"{source}: {_prefixed(str(exc), prefix)}") from None


def _from_yaml(hint: Any, value: Any, source: str, key: str) -> Any:
    """Structure from YAML: sub-mappings of nested classes built, lists made tuples; the
    values themselves are checked by the classes."""
    if typing.get_origin(hint) in (typing.Union, types.UnionType):
        if value is None:
            return None
        hint = _optional_of(hint, key)
    origin = typing.get_origin(hint)
    if isinstance(hint, type) and dataclasses.is_dataclass(hint):
        if not isinstance(value, Mapping):
            raise ConfigError(f"{source}: key '{key}': expected a mapping, got {show(value)}")
        return build(hint, value, source, prefix=key + ".")
    if origin is Mapping and isinstance(value, Mapping):
        if not all(isinstance(name, str) for name in value):
            return value  # the class names the bad key
        item = typing.get_args(hint)[1]
        return {name: _from_yaml(item, v, source, f"{key}.{name}") for name, v in value.items()}
    if origin is tuple and isinstance(value, list):
        return tuple(value)
    return value


def _prefixed(message: str, prefix: str) -> str:
    return message.replace("key '", f"key '{prefix}", 1) if prefix else message


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


# -- overrides -----------------------------------------------------------------------


def parse_override(item: str) -> tuple[str, Any]:
    """``'KEY=VALUE'`` -> (dotted key, value parsed as YAML by the files' loader: ``0.5`` and
    ``5e-1`` floats, ``true`` a bool, ``[1, 2]`` a list, ``abc`` a string); ConfigError (one
    line) for anything else."""
    key, sep, text = item.partition("=")
    key = key.strip()
    parts = key.split(".")
    if not sep or not key or not all(part.strip() for part in parts):
        raise ConfigError(f"override {show(item)}: expected KEY=VALUE with a dotted KEY")
    try:
        value = yaml.load(text, Loader=_StrictLoader) if text.strip() else None
    except _YAML_ERRORS as exc:
        raise ConfigError(
            f"override {show(item)}: the value is not valid YAML ({_one_line(str(exc))})"
        ) from None
    return key, value


def safety_rule_message(source: str, where: str, rule: str) -> str:
    """The one-line refusal of a file or an override that sets a safety rule's key."""
    return f"{source}: {where}: a safety rule, not a setting ({rule}); no setting can loosen it"


def safety_rule_keys(cls: type, prefix: str = "") -> dict[str, str]:
    """The dotted keys of the ``Config`` class ``cls`` and its nested sections that name a
    safety rule (``Config.safety_rules``), each with its rule."""
    keys = {prefix + name: rule for name, rule in getattr(cls, "safety_rules", {}).items()}
    hints = typing.get_type_hints(cls)
    for field in dataclasses.fields(cls):
        for hint in (hints[field.name], *typing.get_args(hints[field.name])):
            if isinstance(hint, type) and issubclass(hint, Config):
                keys.update(safety_rule_keys(hint, f"{prefix}{field.name}."))
    return keys


def apply_overrides(
    raw: Mapping[str, Any],
    items: Sequence[str],
    source: str,
    safety_rules: Mapping[str, str] | None = None,
) -> dict[str, Any]:
    """A deep copy of the raw mapping ``raw`` (as ``load_yaml`` returns it) with each
    ``KEY=VALUE`` of ``items`` set at its dotted path, in order.

    Only keys already in the mapping may be set (a typo is an error, not a new key); the
    values are not checked here but when the mapping is built into its ``Config`` class, as
    for a file. A key of ``safety_rules`` (``safety_rule_keys``) is refused with its rule.
    ConfigError (one line, naming ``source`` and the key) otherwise.
    """
    result = copy.deepcopy(dict(raw))
    for item in items:
        key, value = parse_override(item)
        if safety_rules and key in safety_rules:
            raise ConfigError(safety_rule_message(source, f"override '{key}'", safety_rules[key]))
        node: Any = result
        path = key.split(".")
        for depth, name in enumerate(path):
            where = ".".join(path[:depth])
            if not isinstance(node, dict):
                raise ConfigError(
                    f"{source}: override '{key}': key '{where}' is not a mapping, "
                    f"so it has no key '{name}'"
                )
            if name not in node:
                known = ", ".join(sorted(map(str, node))) or "none"
                within = f" in '{where}'" if where else ""
                raise ConfigError(
                    f"{source}: override '{key}': unknown key '{name}'{within}; "
                    f"expected one of: {known}"
                )
            if depth == len(path) - 1:
                node[name] = value
            else:
                node = node[name]
    return result
