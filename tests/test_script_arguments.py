"""Every script refuses nonsense counts, seeds and outputs with exit code 2 before any work."""

import pytest

from tests.script_runs import script_main


@pytest.mark.parametrize(
    "name,args,message",
    [
        ("bench_estimation", ["--repeats", "0"], "--repeats"),
        ("bench_estimation", ["--repeats", "-1"], "--repeats"),
        ("bench_gel", ["--steps", "0"], "--steps"),
        ("bench_gel", ["--steps", "199"], "--steps"),
        ("bench_gel", ["--repeats", "0"], "--repeats"),
        ("bench_render", ["--repeats", "0"], "--repeats"),
        ("bench_render", ["--repeats", "2.5"], "--repeats"),
        ("bench_slip", ["--frames", "0"], "--frames"),
        ("bench_slip", ["--frames", "9"], "--frames"),
        ("bench_camera_decode", ["--runs", "0"], "--runs"),
        ("bench_camera_decode", ["--seed", "-3"], "--seed"),
        ("demo", ["--seed", "nan"], "--seed"),
        ("bench_insertion_scene", ["--runs", "0"], "--runs"),
        ("bench_insertion_scene", ["--seed", "-3"], "--seed"),
        ("bench_insertion_scene", ["--task", "usb_b"], "--task"),
        ("calibrate_task", ["--task", "usb_c", "--seed", "-3", "--out", "c.yaml"], "--seed"),
        ("calibrate_task", ["--task", "usb_c"], "--out"),
    ],
)
def test_nonsense_counts_are_usage_errors(name, args, message, capsys):
    main = script_main(name)
    with pytest.raises(SystemExit) as stop:
        main(args)
    assert stop.value.code == 2
    assert message in capsys.readouterr().err


@pytest.mark.parametrize("name", ["bench_estimation", "bench_slip"])
@pytest.mark.parametrize("out,message", [("/dev/full", "not a regular file"), (".", "a folder")])
def test_bench_reports_check_their_output_first(name, out, message, capsys):
    main = script_main(name)
    assert main(["--write", out]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"{name}: error: --write") and message in err and "\n" not in err


def test_demo_refuses_an_output_that_is_a_file(tmp_path, capsys):
    (tmp_path / "file").write_text("mine")
    assert script_main("demo")(["--out", str(tmp_path / "file")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("demo: error: --out") and "is a file" in err
    assert (tmp_path / "file").read_text() == "mine"
