"""The benchmark script runs and writes its table (its numbers are not asserted here)."""

from tests.script_runs import exit_code


def test_quick_benchmark_writes_a_report(tmp_path):
    report = tmp_path / "BENCH.md"
    report.write_text("# Benchmarks\n\n## Estimation pipeline\nold\n\n## Camera decoding\nkept\n")
    assert exit_code("bench_estimation", ["--quick", "--write", str(report)]) == 0
    text = report.read_text()
    assert "**paper**" in text and "**default**" in text and "Machine:" in text
    assert "old" not in text and "## Camera decoding\nkept" in text  # other sections survive
