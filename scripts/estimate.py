#!/usr/bin/env python3
"""Offline torque estimation on recorded tactile frames; see controller/offline.py."""

import sys

from controller.offline import main

if __name__ == "__main__":
    sys.exit(main())
