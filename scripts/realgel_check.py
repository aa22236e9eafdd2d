#!/usr/bin/env python3
"""Estimators on real gel textures under an independent elastic model; see
evaluation/realgel/check_cli.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("evaluation.realgel.check_cli")
