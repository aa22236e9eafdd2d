"""A batch refuses a bad setting before any trial, as run_trial does."""

import pytest

from tests.script_runs import exit_code


@pytest.mark.parametrize(
    "override, key",
    [("estimator=nonexistent", "estimator"), ("devices.tactile=/etc/passwd", "devices.tactile")],
)
def test_a_bad_setting_is_exit_2_with_one_line_and_no_trial(tmp_path, override, key, capsys):
    out = tmp_path / "batch"
    args = ["--task", "usb_c", "--seeds", "0:2", "--set", override, "--out", str(out)]
    code = exit_code("run_trials", args)
    captured = capsys.readouterr()
    err = captured.err.strip()
    assert code == 2 and err.startswith("run_trials: error:") and "\n" not in err
    assert f"usb_c.yaml: key '{key}'" in err
    assert not (out / "trials.csv").exists() and "succeeded" not in captured.out
