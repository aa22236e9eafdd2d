"""The insertion scene's benchmark runs its scripted insertion (speed is not asserted)."""

from evaluation.bench.insertion_scene import main, scripted_run


def test_the_scripted_insertion_reaches_the_floor():
    result = scripted_run("usb_c", seed=1, estimate=False)
    assert result.depth_m > 0.006  # the USB-C receptacle is 6.5 mm deep
    assert result.frames > 100 and result.sim_s > 5.0


def test_the_benchmark_prints_its_table_and_its_profile(capsys):
    assert main(["--runs", "1", "--no-estimate", "--task", "usb_a", "--profile"]) == 0
    out = capsys.readouterr().out
    assert "Machine:" in out and "Median:" in out and "| 0 |" in out
    split, profile = out.split("under cProfile")
    assert "| physics |" in split and "| estimator |" not in split  # left out: not timed
    assert "| physics |" in profile and "| function | calls |" in profile
