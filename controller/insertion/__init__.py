"""The insertion state machine: Observation in, Command out, no I/O (see interface.py)."""
