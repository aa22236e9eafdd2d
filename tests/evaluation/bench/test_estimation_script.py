"""The benchmark script runs and writes its table (its numbers are not asserted here)."""

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]


def test_quick_benchmark_writes_a_report(tmp_path):
    report = tmp_path / "BENCH.md"
    report.write_text("# Benchmarks\n\n## Estimation pipeline\nold\n\n## Camera decoding\nkept\n")
    result = subprocess.run(
        [
            sys.executable,
            str(ROOT / "scripts" / "bench_estimation.py"),
            "--quick",
            "--write",
            str(report),
        ],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=300,
    )
    assert result.returncode == 0, result.stderr
    text = report.read_text()
    assert "**paper**" in text and "**default**" in text and "Machine:" in text
    assert "old" not in text and "## Camera decoding\nkept" in text  # other sections survive
