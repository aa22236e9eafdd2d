"""The LeRobot check of an episode export (lerobot_check, ``make check-lerobot``): the real
``lerobot`` loads the export in its own environment. The episode tools themselves are the
product's (``tactile replay``: controller/cli/replay.py, controller/replay/)."""
