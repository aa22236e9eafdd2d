"""The independent real-gel check (docs/BENCHMARKS.md): estimators on real gel textures
deformed by a half-space elastic model the simulator did not make, and the study of the
dipole's origin under pushing."""
