"""Simulated tactile data for the offline tools (``tactile estimate``, ``tactile calibrate``:
controller/cli/, controller/offline/): make a simulated dataset (make_dataset_cli,
jig_dataset), fit a task's calibration in its scene (calibrate_task_cli, scene_calibration),
and the estimator demo (estimator_demo)."""
