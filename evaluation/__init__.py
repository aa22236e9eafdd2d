"""Offline tools and experiments that join the simulator (drivers/sim) and the estimator and
controller; the product (core, drivers, controller) never imports this package. By concern:

* ``common``: what the tools and experiments share (command-line support, output files, the
  machine line, the simulator's pieces and renderer set up by name);
* ``offline``: the user's offline tools on tactile data: estimate, calibrate, make a
  simulated dataset, the estimator demo;
* ``experiments``: the estimator experiments of docs/EVALUATION.md (``make evaluate``);
* ``appearance``: the renderer's look measured on and fitted to real gel captures;
* ``real_recordings``: real-texture recordings rendered, and estimators checked on them;
* ``realgel``: the independent real-gel check (real textures, a half-space elastic model);
* ``bench``: speed benchmarks (docs/BENCHMARKS.md);
* ``trials``: simulated insertion trials, their batches, comparisons and charts;
* ``episodes``: the episode tools (summary, chart, re-estimation, LeRobot export, repair).
"""
