#!/usr/bin/env python3
"""The offline estimator demo on a synthetic sequence (``make estimator-demo``); see
evaluation/offline/estimator_demo.py."""

import sys

from evaluation.offline.estimator_demo import main

if __name__ == "__main__":
    sys.exit(main())
