"""The axial-force map's fit (evaluation/trials/axial_map.py) and its tool, on synthetic trial
records whose true axial force is a known map of the estimate's terms."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from evaluation.trials.axial_map import fit_weights, joined, record_samples, rms_error_n
from evaluation.trials.axial_map_cli import main

WEIGHTS = np.array([10.0, -3.0, 7.0, 0.5, 2.2, 0.1, 8.0, 0.2, 1.9])
CHANNELS = ("tau_x", "tau_y", "tau_z", "shear_x", "shear_y", "normal")


def write_record(folder: Path, seed: int, frames: int = 60) -> Path:
    """A record of ``frames`` new frames (each ticked twice) in SEARCH and INSERT, plus
    APPROACH ticks whose force breaks the map; truth at 100 Hz."""
    rng = np.random.default_rng(seed)
    folder.mkdir(parents=True)
    t_truth = np.arange(0.0, 0.04 * (frames + 10), 0.01)
    force = np.full(len(t_truth), 99.0)  # the map's force at frame times, else nonsense
    ticks = []
    for k in range(frames):
        t_s = 0.04 * k
        values = rng.normal(0.0, [0.01, 0.01, 0.01, 0.5, 0.5, 0.5])
        terms = np.concatenate([values, np.abs(values[:3])])
        force[int(round(t_s / 0.01))] = WEIGHTS @ terms + 3.0  # any intercept
        phase = "approach" if k < 5 else ("search" if k < 40 else "insert")
        estimate = dict(zip(CHANNELS, values.tolist(), strict=True))
        for _ in range(2):
            ticks.append({"t_s": t_s, "phase": phase, "estimate_t_s": t_s, "estimate": estimate})
    (folder / "ticks.jsonl").write_text("\n".join(json.dumps(t) for t in ticks) + "\n")
    wrist = np.zeros((len(t_truth), 6))
    wrist[:, 2] = force
    np.savez(folder / "truth.npz", t_s=t_truth, wrist_wrench_t=wrist)
    return folder


def test_the_fit_recovers_the_map_from_searching_and_pushing_frames_only(tmp_path):
    samples = record_samples(write_record(tmp_path / "a", 1))
    assert len(samples.force_n) == 55  # each frame once, APPROACH's left out
    weights = fit_weights(samples)
    assert weights == pytest.approx(WEIGHTS, rel=1e-6)
    check = record_samples(write_record(tmp_path / "b", 2))
    assert rms_error_n(weights, check) == pytest.approx(0.0, abs=1e-9)
    only_shear = np.zeros(9)
    only_shear[4] = 2.0
    assert rms_error_n(only_shear, check) > 0.05


def test_joined_samples_keep_every_frame(tmp_path):
    a = record_samples(write_record(tmp_path / "a", 1))
    b = record_samples(write_record(tmp_path / "b", 2, frames=30))
    assert len(joined([a, b]).force_n) == 55 + 25


def test_the_tool_prints_the_task_line_and_both_errors(tmp_path, capsys):
    fit = [write_record(tmp_path / f"fit{k}", k) for k in range(2)]
    check = write_record(tmp_path / "check", 9)
    assert main(["--fit", *map(str, fit), "--check", str(check)]) == 0
    out = capsys.readouterr().out.splitlines()
    printed = json.loads(out[0].removeprefix("axial_weights: "))
    assert printed == pytest.approx(WEIGHTS.tolist(), rel=1e-4)
    assert out[2].startswith("RMS error on 1 checked trials (55 frames): fitted 0.000 N")


def test_a_folder_that_is_no_record_is_one_line_and_exit_2(tmp_path, capsys):
    record = write_record(tmp_path / "a", 1)
    (tmp_path / "empty").mkdir()
    assert main(["--fit", str(record), "--check", str(tmp_path / "empty")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "expected a trial record" in err


def test_fit_and_check_records_must_differ(tmp_path, capsys):
    record = write_record(tmp_path / "a", 1)
    assert main(["--fit", str(record), "--check", str(record)]) == 2
    assert "in both --fit and --check" in capsys.readouterr().err


def test_against_weights_must_be_nine_numbers(tmp_path, capsys):
    record = write_record(tmp_path / "a", 1)
    with pytest.raises(SystemExit) as exit_info:
        main(["--fit", str(record), "--check", str(record), "--against", "1,2"])
    assert exit_info.value.code == 2
    assert "expected 9 numbers" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("damage", "message"),
    [
        ("ticks", "ticks.jsonl, line 2: expected a tick record"),
        ("truth", "truth.npz: expected a trial's truth"),
    ],
)
def test_a_damaged_record_names_its_file_in_one_line_and_exit_2(tmp_path, capsys, damage, message):
    good = write_record(tmp_path / "good", 1)
    bad = write_record(tmp_path / "bad", 2)
    if damage == "ticks":
        lines = (bad / "ticks.jsonl").read_text().splitlines()
        (bad / "ticks.jsonl").write_text("\n".join([lines[0], "{not json", *lines[2:]]) + "\n")
    else:
        (bad / "truth.npz").write_bytes(b"not a zip")
    assert main(["--fit", str(bad), "--check", str(good)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err and "Traceback" not in err
