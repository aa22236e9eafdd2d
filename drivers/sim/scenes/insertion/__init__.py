"""The simulated insertion scene (docs/SIMULATION.md, "The insertion
scene"): MuJoCo rigid contacts between a grasped USB plug and a board with a receptacle,
the commanded TCP as a mocap body behind a compliant wrist, the plug in a stiff gel spring
whose wrench drives the gel model and the rendered tactile frames.

Modules: ``scene_config`` (the task YAML's ``scene:``, ``plug:``, ``hole:``), ``draws`` (the
seed's hole, board and grasp), ``frames``, ``mjcf`` (the model text), ``physics`` (MuJoCo
stepping, the grasp's wrench, the truth rows), ``truth`` (``TruthLog``), ``world`` (the
physics in step with the arm and gripper twins), ``coupling`` (grasp wrench -> gel model ->
camera field), ``scene_clock`` (``SceneClock``), ``builder`` (``build_insertion_sim``).
"""

from drivers.sim.scenes.insertion.builder import (
    InsertionSim,
    SimDevices,
    build_insertion_sim,
    build_world,
)
from drivers.sim.scenes.insertion.draws import GraspPose, SceneDraw, draw_scene
from drivers.sim.scenes.insertion.scene_clock import SceneClock
from drivers.sim.scenes.insertion.scene_config import InsertionSceneConfig
from drivers.sim.scenes.insertion.truth import TruthLog

__all__ = [
    "GraspPose", "InsertionSceneConfig", "InsertionSim", "SceneClock", "SceneDraw",
    "SimDevices", "TruthLog", "build_insertion_sim", "build_world", "draw_scene",
]  # fmt: skip
