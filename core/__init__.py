"""The shared core below ``controller`` and ``drivers``: what both read and neither owns.

* ``config``: YAML -> frozen, self-validating dataclasses, overrides, the configs/ lookup;
* ``clock``: the injected clocks (monotonic, manual);
* ``errors``: the typed device error tree;
* ``devices``: the device Protocols (Arm, Gripper, TactileSensor, Gamepad, ...) and the
  status types they exchange (``Pose`` is T2B, ``Twist``, ``ArmStatus``, ...);
* ``task_geometry``: the plug and hole of a task;
* ``sensor_profile``: a visuotactile sensor's image geometry;
* ``spatial``: rotations and tilts with their frames in the names;
* ``quaternion``: unit quaternions as float tuples in closed form (one orientation at a time,
  hundreds of times a second);
* ``envelope``: the workspace box, the tilt limit and the speed limits with their clamps,
  one geometry for the arm driver's envelope and the controller's limiter;
* ``atomic_files``: a result replaces its destination only when complete;
* ``entry_point``: how a script or an installed command runs its tool (Ctrl-C and SIGTERM
  end it with one line at any moment, imports included).

Import rule: ``core`` imports only the standard library, NumPy, SciPy and PyYAML; it never
imports ``controller``, ``drivers`` or ``evaluation`` (tests/test_layers.py).
"""
