#!/usr/bin/env python3
"""Check the configured devices, one line each; see drivers/check_hardware.py."""

import sys

from drivers.check_hardware import main

if __name__ == "__main__":
    sys.exit(main())
