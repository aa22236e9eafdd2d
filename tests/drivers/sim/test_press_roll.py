"""The press-and-roll scene: the ball's footprint, the program and the gel's response."""

import dataclasses

import numpy as np
import pytest

from drivers.sim.scenes.press_roll import (
    PHASES,
    BallGelModel,
    PressRollConfig,
    ball_footprint,
    press_roll_program,
    press_roll_states,
)
from evaluation.common.sim_setup import gel_profile

SHORT = PressRollConfig(open_frames=2, press_frames=4, roll_frames=8, press_rolled_frames=4)


@pytest.fixture(scope="module")
def model():
    return BallGelModel(gel_profile("gelsight_mini"), SHORT.ball_radius_m)


def test_ball_footprint_is_a_sphere(model):
    radius = 0.004
    foot = ball_footprint(model, radius, (0.001, -0.002))
    rho = np.hypot(model.grid.x_m - 0.001, model.grid.y_m + 0.002)
    inside = rho < radius
    assert np.array_equal(foot.mask, inside & (np.abs(model.grid.x_m) < 0.012))
    expected = radius - np.sqrt(radius**2 - rho[inside] ** 2)
    assert np.allclose(foot.sag_m[inside], expected)
    assert np.all(foot.edge_weight[~foot.mask] == 0.0)
    assert np.all((foot.edge_weight >= 0) & (foot.edge_weight <= 1))


def test_program_presses_rolls_then_presses_harder():
    program = press_roll_program(SHORT)
    phases = [step.phase for step in program]
    assert len(program) == 2 + 4 + 2 * 8 + 4
    assert [p for i, p in enumerate(phases) if i == 0 or phases[i - 1] != p] == list(PHASES)
    assert all(step.force_n == 0 for step in program if step.phase == "open")
    press = [step.force_n for step in program if step.phase == "press"]
    assert np.all(np.diff(press) > 0) and press[-1] == pytest.approx(SHORT.force_n)
    rolls = np.array([step.roll_m for step in program if step.phase == "roll"])
    assert np.abs(rolls).max() == pytest.approx(SHORT.roll_m, rel=0.05)
    assert np.all(rolls[:8, 1] == 0) and np.all(rolls[8:, 0] == 0)  # along x, then along y
    harder = [step.force_n for step in program if step.phase == "press_rolled"]
    assert max(harder) == pytest.approx(SHORT.harder * SHORT.force_n, rel=0.05)
    step = program[-3]
    assert step.wrench.tau_x == pytest.approx(step.force_n * step.roll_m[1])
    assert step.wrench.tau_y == pytest.approx(-step.force_n * step.roll_m[0])


def test_the_gel_carries_the_press_with_its_centre_of_pressure_where_asked(model):
    program = press_roll_program(SHORT)
    states = press_roll_states(model, program)
    for step, state in zip(program, states, strict=True):
        force = state.normal.force_n
        assert state.normal.balanced
        assert force.sum() == pytest.approx(step.force_n, rel=1e-6, abs=1e-9)
        if step.force_n > 0:
            centre = (
                np.array([(force * model.grid.x_m).sum(), (force * model.grid.y_m).sum()])
                / force.sum()
            )
            assert centre == pytest.approx(step.roll_m, abs=1e-8)
    contact = [int(s.in_contact.sum()) for s, p in zip(states, program, strict=True)]
    assert contact[0] == 0 and contact[5] > contact[3] > 0  # the patch grows with the press


def test_bad_configuration_names_the_key():
    with pytest.raises(ValueError, match="roll_m"):
        dataclasses.replace(SHORT, roll_m=-0.001)
