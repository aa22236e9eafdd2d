"""The insertion scene before issue 24 made it need touch, as task overrides: the plug
exactly in the grasp as the machine assumes, the board at its nominal height and level,
and the old soft wrist (0.5 N*m/rad, 11 N/m sideways at the tip). The hole's x, y and yaw
are still drawn, and the camera keeps its latency and effects.

For tests of the trial machinery (records, faults, signals, take-over) that need the
machine to reach INSERT or DONE, not of the machine's success on the drawn scene, which is
the insertion trials' to measure (docs/TRIALS.md)."""

EASY_SCENE = (
    "scene.grasp_uncertainty.tilt_rad=0",
    "scene.grasp_uncertainty.along_m=0",
    "scene.grasp_uncertainty.across_m=0",
    "scene.board_uncertainty.height_m=0",
    "scene.board_uncertainty.tilt_rad=0",
    "scene.wrist.tilt_stiffness_nm_rad=0.5",
    "scene.wrist.tilt_damping_nm_s_rad=0.005",
)
