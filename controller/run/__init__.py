"""The run path: a task file -> devices (through the registry) -> the controller by name ->
the control loop -> observers. Product code: it runs an insertion on the simulator or on the
robot, and never imports the simulator (docs/ARCHITECTURE.md, "The run path").

* ``task``: the task file's schema and ``load_task``;
* ``controllers``: the table of controllers (a machine and its wrench source, by name);
* ``record``: the run's record, a tick observer;
* ``runner``: ``run_task``.
"""

from controller.run.controllers import CONTROLLERS, Controller
from controller.run.runner import RunOutcome, run_task
from controller.run.task import Task, TaskConfig, load_task

__all__ = [
    "CONTROLLERS", "Controller", "RunOutcome", "Task", "TaskConfig", "load_task", "run_task",
]  # fmt: skip
