"""Gamepad scripts for the simulated pad (``--script FILE`` of tactile teleop).

A script is YAML with one key, ``events``: a list in time order, each a mapping with

* ``t_s`` (required): seconds from the demo's start on its clock (the simulated world's);
* ``axes``: action name -> value in [-1, 1] (the mapping's axis actions, e.g. ``vy``);
* ``buttons``: action name -> true / false (e.g. ``deadman``, ``estop``, ``estop_ack``,
  ``hand_back``, ``gripper_open``);
* ``attached``: false unplugs the pad, true plugs it back in.

An action keeps its value until an event changes it; the pad starts neutral (axes 0,
buttons released). ``drivers.sim.twins.gamepad.PadEvent`` checks each event's values;
``load_pad_script`` checks the times are in order and, given the mapping's action names,
that each event names only those, so a bad script is one ``ConfigError`` line naming the
file and the event before anything runs. configs/teleop/alignment_demo.yaml is the default
script.
"""

from __future__ import annotations

from collections.abc import Collection
from pathlib import Path
from typing import Any

from core.config import ConfigError, load_yaml
from drivers.sim.twins.gamepad import PadEvent

EVENT_KEYS = ("t_s", "axes", "buttons", "attached")


def load_pad_script(
    path: Path | str,
    axes: Collection[str] | None = None,
    buttons: Collection[str] | None = None,
) -> tuple[PadEvent, ...]:
    """The events of the script at ``path``; ConfigError (one line, naming the file and the
    event) for anything malformed: a bad value, a time before the previous event's, and
    (when the mapping's ``axes`` and ``buttons`` action names are given) an action the
    mapping does not have."""
    source = str(path)
    data = load_yaml(path)
    if not isinstance(data, dict) or set(data) != {"events"}:
        raise ConfigError(f"{source}: expected one key 'events' (a list of events)")
    events = data["events"]
    if not isinstance(events, list) or not events:
        raise ConfigError(f"{source}: key 'events': expected a non-empty list")
    parsed = tuple(_event(source, i, raw) for i, raw in enumerate(events))
    for index, event in enumerate(parsed):
        where = f"{source}: events[{index}] (t_s {event.t_s:g})"
        if index and event.t_s < parsed[index - 1].t_s:
            raise ConfigError(
                f"{where}: expected times in increasing order, but the event before is at "
                f"{parsed[index - 1].t_s:g} s"
            )
        for kind, known, named in (("axes", axes, event.axes), ("buttons", buttons, event.buttons)):
            unknown = [] if known is None else sorted(set(named) - set(known))
            if unknown:
                raise ConfigError(
                    f"{where}: key '{kind}': unknown action '{unknown[0]}'; the pad's mapping "
                    f"has {', '.join(known or ())}"
                )
    return parsed


def _event(source: str, index: int, raw: Any) -> PadEvent:
    where = f"{source}: events[{index}]"
    if not isinstance(raw, dict) or "t_s" not in raw:
        raise ConfigError(f"{where}: expected a mapping with 't_s'")
    unknown = sorted(set(raw) - set(EVENT_KEYS))
    if unknown:
        raise ConfigError(f"{where}: unknown key '{unknown[0]}'; expected {', '.join(EVENT_KEYS)}")
    attached = raw.get("attached")
    if attached is not None and not isinstance(attached, bool):
        raise ConfigError(f"{where}: key 'attached': expected true or false, got {attached!r}")
    t_s = raw["t_s"]
    if isinstance(t_s, bool) or not isinstance(t_s, int | float):
        raise ConfigError(f"{where}: key 't_s': expected a time in s, got {t_s!r}")
    for key in ("axes", "buttons"):
        if not isinstance(raw.get(key, {}), dict):
            raise ConfigError(f"{where}: key '{key}': expected a mapping of action -> value")
    try:
        return PadEvent(float(t_s), raw.get("axes", {}), raw.get("buttons", {}), attached)
    except ValueError as error:
        raise ConfigError(f"{where}: {error}") from None
