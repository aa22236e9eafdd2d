"""The teleoperated alignment demo (scripts/teleop_demo.py): its command line, its gamepad
scripts and the manoeuvres' torque signs."""
