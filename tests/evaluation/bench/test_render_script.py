"""The renderer benchmark runs and prints every case (its numbers are not asserted here)."""

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]


def test_render_benchmark_prints_each_case():
    result = subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "bench_render.py"), "--repeats", "3"],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=120,
    )
    assert result.returncode == 0, result.stderr
    for case in ("no effects | 48x64", "noise + drift + blur", "motion blur, 2 samples"):
        assert case in result.stdout
    assert "| no effects | 240x320 |" in result.stdout and "Machine:" in result.stdout
