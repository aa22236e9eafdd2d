"""Pictures of the teleoperated alignment demo (``tactile teleop``,
controller/cli/alignment_demo.py): the live view's screenshot at a moment of an episode and
the manoeuvres' sign drawing."""
