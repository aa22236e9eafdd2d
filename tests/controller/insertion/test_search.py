"""SEARCH's load-drop rule (search.HoleDetector): the axial force falling while the TCP's
height is held means the tip dropped into the opening."""

from dataclasses import replace
from types import SimpleNamespace

import numpy as np
from scipy.spatial.transform import Rotation

from controller.insertion.machine_config import SearchSettings
from controller.insertion.search_path import HoleDetector

UPRIGHT = Rotation.from_euler("x", np.pi)
STILL = np.zeros(3)  # no drag: only the load-drop rule can fire


def feed(detector: HoleDetector, loads: list[float], t0_s: float = 0.0) -> list[str]:
    found = []
    for i, load in enumerate(loads):
        signals = SimpleNamespace(axial_force_sigma=load, torque_t=np.zeros(3))
        found.append(detector.update(signals, UPRIGHT, STILL, t0_s + 0.04 * i))
    return found


def test_a_load_drop_is_the_hole_after_hole_frames_estimates():
    settings = SearchSettings()
    detector = HoleDetector(settings, 0.4)
    assert not any(feed(detector, [20.0] * 30))
    assert abs(detector.load_reference - 20.0) < 1e-9
    found = feed(detector, [8.0] * settings.hole_frames, t0_s=1.2)
    assert found == [""] * (settings.hole_frames - 1) + ["load_drop"]


def test_a_small_or_brief_drop_is_not_the_hole():
    settings = SearchSettings()
    detector = HoleDetector(settings, 0.4)
    feed(detector, [20.0] * 30)
    brief = [8.0] * (settings.hole_frames - 1) + [20.0]
    assert not any(feed(detector, brief * 5, t0_s=1.2))
    light = HoleDetector(settings, 0.4)
    feed(light, [5.0] * 30)  # a drop to 2 is 60 % but only 3 noise units
    assert not any(feed(light, [2.0] * 10, t0_s=1.2))


def test_no_drop_is_judged_while_settling_and_ratio_zero_turns_it_off():
    settings = SearchSettings()
    detector = HoleDetector(settings, 0.4)
    assert not any(feed(detector, [20.0] * 3 + [1.0] * 8))  # within settle_s
    off = HoleDetector(replace(settings, hole_drop_ratio=0.0), 0.4)
    feed(off, [20.0] * 30)
    assert not any(feed(off, [1.0] * 10, t0_s=1.2))
