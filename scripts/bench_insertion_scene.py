#!/usr/bin/env python3
"""Speed of the simulated insertion scene on one thread; evaluation/bench/insertion_scene.py."""

import sys

from evaluation.common.machine_info import one_thread_env

one_thread_env()  # before NumPy loads its BLAS

from evaluation.bench.insertion_scene import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
