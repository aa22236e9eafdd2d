#!/usr/bin/env python3
"""The dipole's origin under pushing, on the true field; see evaluation/realgel/origins_cli.py."""

from core.entry_point import run_main

if __name__ == "__main__":
    run_main("evaluation.realgel.origins_cli")
