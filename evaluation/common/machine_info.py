"""What runs a measurement: one thread, and the line that names the CPU, the libraries and the
git revision in the reports of the benchmarks (evaluation/bench/) and of the evaluation
(evaluation/experiments/run.py). Importing it loads no numerical library, so
``one_thread_env`` can run first."""

from __future__ import annotations

import datetime
import os
import platform
from pathlib import Path

from core.provenance import git_revision

THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


def one_thread_env() -> None:
    """Limit OpenMP, OpenBLAS and MKL to one thread in this process (call it before NumPy
    loads its BLAS) and in the processes it starts."""
    for name in THREAD_VARIABLES:
        os.environ[name] = "1"


def cpu_model() -> str:
    """The CPU's model name (Linux: /proc/cpuinfo), or what ``platform`` knows of it."""
    try:
        return next(
            line.split(":", 1)[1].strip()
            for line in Path("/proc/cpuinfo").read_text().splitlines()
            if line.startswith("model name")
        )
    except (OSError, StopIteration):
        return platform.processor() or platform.machine() or "unknown CPU"


def describe_machine(measured_on: str) -> str:
    """One line for a report's "Machine:": the CPU, its architecture and the cores this
    process may use, ``measured_on`` (how the measurement was threaded, e.g. "1 thread"), the
    Python, NumPy, SciPy and OpenCV versions, the git revision and today's date."""
    import cv2
    import numpy as np
    import scipy

    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    return (
        f"{cpu_model()}; {platform.machine()}, {cores} cores visible, measured on {measured_on}; "
        f"Python {platform.python_version()}, NumPy {np.__version__}, SciPy {scipy.__version__}, "
        f"OpenCV {cv2.__version__}; git {git_revision()}; {datetime.date.today().isoformat()}"
    )
