"""An easier insertion scene, as task overrides: the plug exactly in the grasp as the
machine assumes and the board at its nominal height and level. The hole's x, y and yaw are
still drawn, the wrist is the scene's, and the camera keeps its latency and effects. (The
old soft wrist is not used: its torques say too little for the machine's ALIGN, which now
feels the opening's walls.)

For tests of the trial machinery (records, faults, signals, take-over) that need the
machine to reach INSERT or DONE, not of the machine's success on the drawn scene, which is
the insertion trials' to measure (docs/TRIALS.md).

The suite's ``easy_task(name)`` fixture (tests/conftest.py) loads a task on the easy scene
with a calibration fitted in it, once per test run: the task's own calibration was fitted for
the full scene's drawn grasp and is refused on another grasp
(controller/run/task_calibration.py)."""

from pathlib import Path

from controller.run.task import Task, load_task
from evaluation.offline.scene_calibration import fit_scene_calibration, record_in_scene

EASY_SCENE = (
    "scene.grasp_uncertainty.tilt_rad=0",
    "scene.grasp_uncertainty.along_m=0",
    "scene.grasp_uncertainty.across_m=0",
    "scene.board_uncertainty.height_m=0",
    "scene.board_uncertainty.tilt_rad=0",
)


def write_easy_calibration(name: str, folder: Path) -> None:
    """Fits task ``name``'s calibration on the easy scene into ``folder/<name>.yaml``."""
    task = load_task(name, EASY_SCENE, with_calibration=False)
    folder.mkdir(parents=True)
    calibration = fit_scene_calibration(record_in_scene(task, 0), task)
    (folder / f"{name}.yaml").write_text(calibration.to_yaml())


def easy_scene_task(name: str, calibrations: Path) -> Task:
    """Task ``name`` on the easy scene, with the calibration in ``calibrations``."""
    return load_task(name, (*EASY_SCENE, f"calibration={calibrations / f'{name}.yaml'}"))
