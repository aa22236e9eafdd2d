#!/usr/bin/env python3
"""The offline estimator demo on a synthetic sequence (``make estimator-demo``); see
evaluation/offline/estimator_demo.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("evaluation.offline.estimator_demo")
