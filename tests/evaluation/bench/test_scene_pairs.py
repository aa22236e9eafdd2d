"""The scene benchmark against another checkout: runs paired per seed in fresh processes,
the order alternating, rows parsed, failures named in one line (speed is not asserted)."""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

from controller.cli.support import ToolError
from evaluation.bench.insertion_scene import main
from evaluation.bench.scene_pairs import SCRIPT, SideRun, paired_runs, parse_row, run_side

TABLE = """Machine: x
| seed | sim s | wall s | x real time | CPU s | x per CPU s | frames | depth mm |
|---|---|---|---|---|---|---|---|
| 4 | 7.59 | 2.00 | 3.8 | 1.52 | 5.0 | 166 | 6.50 |
"""


def fake_checkout(folder: Path, cpu_s: float, log: Path, exit_code: int = 0) -> Path:
    """A checkout whose benchmark prints one canned row per call and logs its calls."""
    script = folder / SCRIPT
    script.parent.mkdir(parents=True)
    script.write_text(
        textwrap.dedent(
            f"""
            import sys
            seed = sys.argv[sys.argv.index("--seed") + 1]
            with open({str(log)!r}, "a") as handle:
                handle.write({folder.name!r} + " " + seed + " " + " ".join(sys.argv[1:]) + "\\n")
            if {exit_code}:
                print("bench_insertion_scene: error: broken", file=sys.stderr)
                sys.exit({exit_code})
            print(f"| {{seed}} | 7.50 | 2.50 | 3.0 | {cpu_s:.2f} | 0.0 | 166 | 6.50 |")
            """
        )
    )
    return folder


def test_a_row_is_parsed_for_its_seed():
    assert parse_row(TABLE, 4) == SideRun(7.59, 2.0, 1.52, 166, 0.0065)
    with pytest.raises(ValueError, match="no table row for seed 5"):
        parse_row(TABLE, 5)


def test_the_sides_alternate_and_each_gets_the_options(tmp_path):
    log = tmp_path / "calls.log"
    this = fake_checkout(tmp_path / "this", 1.5, log)
    other = fake_checkout(tmp_path / "other", 3.0, log)
    pairs = list(paired_runs(other, range(2, 5), ["--task", "usb_a"], this=this))
    assert [(seed, mine.cpu_s, theirs.cpu_s) for seed, mine, theirs in pairs] == [
        (2, 1.5, 3.0),
        (3, 1.5, 3.0),
        (4, 1.5, 3.0),
    ]
    calls = [line.split(" ")[:2] for line in log.read_text().splitlines()]
    assert calls == [
        ["this", "2"], ["other", "2"], ["other", "3"], ["this", "3"], ["this", "4"], ["other", "4"],
    ]  # fmt: skip
    assert all(line.endswith("--task usb_a") for line in log.read_text().splitlines())
    assert pairs[0][1].cpu_speed_x == pytest.approx(5.0)


def test_a_failing_side_is_named_in_one_line(tmp_path):
    broken = fake_checkout(tmp_path / "broken", 1.0, tmp_path / "log", exit_code=2)
    with pytest.raises(ToolError, match=r"broken' failed on seed 0 \(exit 2\): .*error: broken"):
        run_side(broken, 0, [])


def test_the_benchmark_against_another_checkout_prints_the_pairs(tmp_path, capsys):
    other = fake_checkout(tmp_path / "other", 100.0, tmp_path / "log")
    args = ["--runs", "1", "--seed", "1", "--no-estimate", "--task", "usb_a"]
    assert main([*args, "--against", str(other)]) == 0
    out = capsys.readouterr().out
    row = next(line for line in out.splitlines() if line.startswith("| 1 |"))
    cells = [cell.strip() for cell in row.strip("|").split("|")]
    assert float(cells[1]) > 1.0 and cells[2] == "0.1"  # this side really ran; 7.5 / 100
    assert "median paired ratio" in out and "Load average" in out


def test_a_folder_without_the_benchmark_is_refused(tmp_path, capsys):
    assert main(["--runs", "1", "--against", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("bench_insertion_scene: error: --against") and "\n" not in err
    assert f"no {SCRIPT} there" in err


def test_an_override_reaches_the_task(capsys):
    assert main(["--runs", "1", "--set", "scene.nope=1"]) == 2
    assert "scene.nope" in capsys.readouterr().err
