"""The press-tilt-release program."""

import numpy as np
import pytest

from drivers.sim.gel.model import GelModel
from drivers.sim.gel.profile import SHAPES, gel_profile
from drivers.sim.scenes.press_tilt import PressTiltConfig, press_tilt_program, press_tilt_states

CONFIG = PressTiltConfig(open_frames=3, press_frames=4, tilt_frames=5, release_frames=4)


def test_the_program_runs_open_press_tilts_release_open():
    program = press_tilt_program(CONFIG)
    segments = [step.segment for step in program]
    expected = (
        ["open"] * 3
        + ["press"] * 4
        + ["tilt_x+"] * 5
        + ["tilt_x-"] * 5
        + ["tilt_y+"] * 5
        + ["tilt_y-"] * 5
        + ["release"] * 4
        + ["open"] * 3
    )
    assert segments == expected
    grips = np.array([step.grip_n for step in program])
    assert grips[:3].max() == 0.0 and grips[-3:].max() == 0.0
    assert grips[6] == pytest.approx(CONFIG.grip_n) and np.all(np.diff(grips[2:7]) > 0)
    tau = np.array([[step.tau_x_nm, step.tau_y_nm] for step in program])
    assert np.abs(tau).max() == pytest.approx(CONFIG.tilt_nm, rel=0.1)
    assert tau[7:12, 0].min() > 0 and tau[12:17, 0].max() < 0 and not tau[7:17, 1].any()
    assert tau[17:22, 1].min() > 0 and tau[22:27, 1].max() < 0 and not tau[17:27, 0].any()
    assert program[1].t_s == pytest.approx(1 / CONFIG.rate_hz)


def test_the_gel_touches_only_while_gripped():
    model = GelModel(gel_profile("gelsight_mini"), SHAPES["plate"])
    program = press_tilt_program(CONFIG)
    states = press_tilt_states(model, program)
    contact = [bool(s.in_contact.any()) for s in states]
    assert contact == [step.grip_n > 0 for step in program]
    carried = np.array([[s.carried.tau_x, s.carried.tau_y] for s in states])
    applied = np.array([[step.tau_x_nm, step.tau_y_nm] for step in program])
    np.testing.assert_allclose(carried, applied, atol=1e-6)
