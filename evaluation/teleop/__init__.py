"""The teleoperated alignment demo (tactile teleop): its command line, its gamepad
scripts and the manoeuvres' torque signs."""
