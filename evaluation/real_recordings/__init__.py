"""Real-texture recordings (docs/BENCHMARKS.md): the press-tilt-release program rendered
on real gel captures (recording_video), the checks of an estimate on one
(recording_checks) and the tool that does both (recordings_cli)."""
