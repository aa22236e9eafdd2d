"""Benchmarks: the speed (and, for the estimator, the field accuracy) of each stage, median over
many runs with the machine noted; their reports go into docs/BENCHMARKS.md. Run them through
scripts/bench_*.py; speed is never asserted in the tests."""
