"""A batch refuses a bad setting before any trial, as run_trial does (issue 22, defect 4)."""

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3]
BATCH = [sys.executable, str(ROOT / "scripts" / "run_trials.py"), "--task", "usb_c"]


@pytest.mark.parametrize(
    "override, key",
    [("estimator=nonexistent", "estimator"), ("devices.tactile=/etc/passwd", "devices.tactile")],
)
def test_a_bad_setting_is_exit_2_with_one_line_and_no_trial(tmp_path, override, key):
    out = tmp_path / "batch"
    command = [*BATCH, "--seeds", "0:2", "--set", override, "--out", str(out)]
    result = subprocess.run(command, capture_output=True, text=True, cwd=ROOT, timeout=120)
    err = result.stderr.strip()
    assert result.returncode == 2 and err.startswith("run_trials: error:") and "\n" not in err
    assert f"usb_c.yaml: key '{key}'" in err
    assert not (out / "trials.csv").exists() and "succeeded" not in result.stdout
