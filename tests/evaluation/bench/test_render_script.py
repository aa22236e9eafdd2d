"""The renderer benchmark runs and prints every case (its numbers are not asserted here)."""

from tests.script_runs import exit_code


def test_render_benchmark_prints_each_case(capsys):
    assert exit_code("bench_render", ["--repeats", "3"]) == 0
    out = capsys.readouterr().out
    for case in ("no effects | 48x64", "noise + drift + blur", "motion blur, 2 samples"):
        assert case in out
    assert "| no effects | 240x320 |" in out and "Machine:" in out
