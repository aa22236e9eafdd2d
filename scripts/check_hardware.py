#!/usr/bin/env python3
"""Check the configured devices, one line each; see drivers/check_hardware.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("drivers.check_hardware")
