"""Research, figure and benchmark tools that join the simulator (drivers/sim) with the
estimator and the controller, scored against the simulator's truth; the product (core,
drivers, controller) never imports this package. ``python -m evaluation TOOL`` runs a tool
(evaluation/tools.py). By concern:

* ``common``: what the tools and experiments share (the machine line, the simulator's pieces
  and renderer set up by name);
* ``offline``: simulated tactile data: a simulated dataset, a task's calibration fitted in its
  scene, the estimator demo;
* ``experiments``: the estimator experiments of docs/EVALUATION.md (``make evaluate``);
* ``appearance``: the renderer's look measured on and fitted to real gel captures;
* ``real_recordings``: real-texture recordings rendered, and estimators checked on them;
* ``realgel``: the independent real-gel check (real textures, a half-space elastic model);
* ``bench``: speed benchmarks (docs/BENCHMARKS.md);
* ``trials``: simulated insertion trials scored against the truth, their batches,
  comparisons and charts;
* ``teleop``: pictures of the teleop demo;
* ``episodes``: the LeRobot check of an episode export.
"""
