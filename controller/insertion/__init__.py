"""The insertion state machine: Observation in, Command out, no I/O (see interface.py).

``InsertionMachine(config, plug, hole)`` is the machine; ``machine_setup_from_task(data,
source)`` reads its ``plug:``, ``hole:`` and ``machine:`` sections from a task file's mapping.
"""

from controller.insertion.config import (
    HolePose,
    MachineConfig,
    MachineSetup,
    PlugGeometry,
    machine_setup_from_task,
)
from controller.insertion.definition import INSERTION, Definition, DefinitionError, Edge
from controller.insertion.interface import (
    Command,
    FailureReason,
    GripperTarget,
    Machine,
    Observation,
    Phase,
    TeleopInput,
    Transition,
)
from controller.insertion.machine import InsertionMachine

__all__ = [
    "INSERTION", "Command", "Definition", "DefinitionError", "Edge", "FailureReason",
    "GripperTarget", "HolePose", "InsertionMachine", "Machine", "MachineConfig",
    "MachineSetup", "Observation", "Phase", "PlugGeometry", "TeleopInput", "Transition",
    "machine_setup_from_task",
]  # fmt: skip
