"""The insertion state machines: Observation in, Command out, no I/O (see interface.py).

``InsertionMachine(config, plug, hole)`` is the find-align-insert machine (the ``align``
controller); the product's press spiral is in ``spiral/``. Its ``machine:`` section, with the
task's ``plug:`` and ``hole:``, is read by the task file's schema (controller/run/task.py).
"""

from controller.insertion.definition import INSERTION, Definition, DefinitionError, Edge
from controller.insertion.interface import (
    Command,
    FailureReason,
    GripperTarget,
    InHandEstimate,
    Machine,
    Observation,
    Phase,
    TeleopInput,
    Transition,
)
from controller.insertion.machine import InsertionMachine
from controller.insertion.machine_config import MachineConfig
from core.task_geometry import HolePose, PlugGeometry

__all__ = [
    "INSERTION", "Command", "Definition", "DefinitionError", "Edge", "FailureReason",
    "GripperTarget", "HolePose", "InHandEstimate", "InsertionMachine", "Machine", "MachineConfig",
    "Observation", "Phase", "PlugGeometry", "TeleopInput", "Transition",
]  # fmt: skip
