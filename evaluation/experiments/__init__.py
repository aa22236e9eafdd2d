"""The estimator experiments of docs/EVALUATION.md, run by ``make evaluate`` (run.py): the
calibration runs, the speed-accuracy front, the stability sweeps and slip detection, plus the
press-and-roll check of the tilt estimate."""
