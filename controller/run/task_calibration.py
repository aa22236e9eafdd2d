"""A task's calibration: the estimator's per-axis fit for the grasped plug, fitted in the
task's scene (``python -m evaluation calibrate_task``) and named by the task file's ``calibration:``
key (a path relative to configs/, e.g. ``calibrations/usb_c.yaml``).

The file records what it was fitted for: the sensor profile, the estimator configuration's
fingerprint (``estimator_sha256``) and the fingerprint of the grasp's scene
(``scene_sha256``, ``grasp_scene_sha256`` below). A task whose calibration was fitted for
another sensor, estimator or grasp is refused when it loads, with one line naming the task
file, the key and the command that fits it again.

The grasp's scene is what the fit depends on: the task's ``scene:`` but the keys that place
the world around the grasp (``OUTSIDE_THE_GRASP``: the board, the hole's draw, contacts and
friction with the board, the wrist that carries the gripper, the start height or depth and
the truth's rate), the plug's geometry, the grip force and the tactile camera's file. So an
easier or harder search (``--set scene.hole_uncertainty.yaw_rad=0``) keeps the calibration,
and a change to the gel, the sensor or the grasp asks for a new one.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from controller.tactile.calibration import Calibration
from controller.tactile.settings import EstimatorConfig
from core.config import CONFIG_ROOT, ConfigError

OUTSIDE_THE_GRASP = (
    "board",
    "hole_uncertainty",
    "friction",
    "contact",
    "wrist",
    "start_above_hole_m",
    "start_depth_m",
    "truth_rate_hz",
)
"""Keys of ``scene:`` that do not change the grasped plug's tactile response."""


def grasp_scene_sha256(raw: Mapping[str, Any], tactile_config: Any) -> str:
    """The fingerprint of the grasp's scene (module doc) of the task mapping ``raw`` (merged,
    overrides applied) with the tactile camera's configuration ``tactile_config`` (a
    dataclass): SHA-256 of the parts as sorted JSON."""
    scene = {k: v for k, v in raw.get("scene", {}).items() if k not in OUTSIDE_THE_GRASP}
    gripper = raw.get("machine", {}).get("gripper", {})
    document = {
        "scene": scene,
        "plug": raw.get("plug"),
        "grip_force_n": gripper.get("close_force_n"),
        "tactile": dataclasses.asdict(tactile_config),
    }
    text = json.dumps(document, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()


def calibration_path(name: str) -> Path:
    """The calibration file ``name`` (relative to configs/, or absolute)."""
    path = Path(name)
    return path if path.is_absolute() else CONFIG_ROOT / path


def load_task_calibration(
    source: str,
    name: str,
    sensor: str,
    estimator: EstimatorConfig,
    scene_sha256: str | None,
    task: str,
) -> Calibration:
    """The calibration file ``name`` of the task file ``source`` (task ``task``), checked
    against the ``sensor`` profile's name, the ``estimator`` configuration and the grasp's
    scene fingerprint (None: not checked, on hardware); ConfigError (one line naming
    ``source`` and the key) otherwise."""
    path = calibration_path(name)
    refit = f"re-run python -m evaluation calibrate_task --task {task} --out {path}"
    if not path.is_file():
        raise ConfigError(f"{source}: key 'calibration': {path} does not exist; {refit}")
    try:
        calibration = Calibration.load(path)
    except ConfigError as exc:
        raise ConfigError(f"{source}: key 'calibration': {exc}") from None
    problem = calibration.mismatch(sensor, estimator)
    fitted = calibration.scene_sha256
    if problem is None and scene_sha256 is not None:
        if fitted is None:
            problem = "it was not fitted in a task's scene"
        elif fitted != scene_sha256:
            problem = (
                f"it was fitted in another scene (grasp fingerprint {fitted[:12]}, "
                f"this task's {scene_sha256[:12]})"
            )
    if problem is not None:
        raise ConfigError(f"{source}: key 'calibration': {path}: {problem}; {refit}")
    return calibration
