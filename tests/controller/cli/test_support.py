"""The tools' number arguments: exponents without a dot are numbers; inf and nan are not."""

import argparse

import pytest

from controller.cli.support import number, number_list
from evaluation.trials.compare import main as compare_main


@pytest.mark.parametrize("text, value", [("5e-1", 0.5), ("1e-05", 1e-05), ("1E3", 1000.0)])
def test_a_number_with_an_exponent_is_a_number(text, value):
    assert number(0.0, 1e6)(text) == value
    assert number_list(0.0, 1e6, "m/s")(f"{text},2") == (value, 2.0)


@pytest.mark.parametrize("text", ["inf", "nan", "-inf", "1e999", "0x10", "five"])
def test_infinities_nan_and_words_stay_refused(text):
    with pytest.raises(argparse.ArgumentTypeError, match="expected a number"):
        number(0.0, 1e6)(text)


def test_a_speed_with_an_exponent_reaches_the_task_as_a_number(tmp_path, capsys):
    """compare_trials passes each speed to the task as --set KEY=1e-05: a number, out of range."""
    args = ["--task", "usb_c", "--seeds", "0:1", "--speeds", "0.00001", "--out", str(tmp_path)]
    assert compare_main(args) == 2
    err = capsys.readouterr().err
    assert "key 'machine.insert.speed_m_s': expected a number in" in err and "got 1e-05" in err
