"""The insertion machine's phases, one module each (``grasp``, ``approach``, ``search``,
``align``, ``insert``, ``backoff``, ``release``, ``retract``, and ``overrides`` for TELEOP,
ESTOP and the terminal phases).

Each module names its phase's sub-stages (an Enum, listed in the checked definition,
``definition.py``), types what the phase remembers while in it (a dataclass made fresh by
``enter`` on every entry) and decides a tick's command in ``step(machine, obs, new)``;
``machine.py`` dispatches to it and owns the transitions.
"""
