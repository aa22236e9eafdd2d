"""The control loop's wrench source (controller/tactile/wrench_source.py): the estimator and
the tests' scripted stand-in both satisfy it."""

import inspect

from controller.loop import ControlLoop
from controller.tactile import TactileEstimator, WrenchSource, estimator_for_sensor
from tests.controller.conftest import ScriptedEstimator


def test_the_estimator_is_a_wrench_source():
    assert isinstance(estimator_for_sensor("gelsight_mini"), WrenchSource)
    for name in ("push", "capture_open", "rezero"):
        ours = inspect.signature(getattr(TactileEstimator, name))
        protocol = inspect.signature(getattr(WrenchSource, name))
        assert list(ours.parameters) == list(protocol.parameters), name


def test_the_scripted_stand_in_is_a_wrench_source():
    assert isinstance(ScriptedEstimator(), WrenchSource)


def test_the_loop_takes_a_wrench_source():
    assert inspect.signature(ControlLoop).parameters["estimator"].annotation == "WrenchSource"
