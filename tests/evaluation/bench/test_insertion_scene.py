"""The insertion scene's benchmark runs its scripted insertion (speed is not asserted)."""

from evaluation.bench.insertion_scene import main, scripted_run
from evaluation.bench.run_fingerprint import RunFingerprint


def test_the_scripted_insertion_reaches_the_floor():
    result = scripted_run("usb_c", seed=1, estimate=False)
    assert result.depth_m > 0.006  # the USB-C receptacle is 6.5 mm deep
    assert result.frames > 100 and result.sim_s > 5.0


def test_the_benchmark_prints_its_table_fingerprint_and_profile(capsys):
    args = ["--runs", "1", "--no-estimate", "--task", "usb_a", "--fingerprint", "--profile"]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "Machine:" in out and "Median:" in out and "| 0 |" in out
    assert "| seed | frames | estimates | truth |" in out
    split, profile = out.split("under cProfile")
    assert "| physics |" in split and "| estimator |" not in split  # left out: not timed
    assert "| physics |" in profile and "| function | calls |" in profile


def test_a_fingerprint_tells_runs_apart_and_alike():
    """Two runs of one seed give one fingerprint; another seed's frames and truth differ."""
    first, again, other = (
        scripted_run("usb_c", seed, estimate=True, fingerprint=RunFingerprint()).digests
        for seed in (2, 2, 3)
    )
    assert first == again
    assert first is not None and other is not None
    assert first["frames"] != other["frames"] and first["truth"] != other["truth"]
