"""The calibration-jig scene: program, timing, load sharing, configuration errors."""

import dataclasses

import numpy as np
import pytest

from drivers.sim.scenes.jig import Experiment, JigGel, ft_samples, jig_program, tactile_times
from evaluation.common.sim_setup import gel_model, jig_config

EXPERIMENTS = [Experiment("x", 0.02, 2), Experiment("y", 0.04, 2)]


def test_program_is_seeded_and_deterministic():
    config = jig_config()
    a = jig_program(EXPERIMENTS, config, np.random.default_rng(3))
    b = jig_program(EXPERIMENTS, config, np.random.default_rng(3))
    c = jig_program(EXPERIMENTS, config, np.random.default_rng(4))
    assert np.array_equal(a.wrench, b.wrench)
    assert not np.array_equal(a.wrench, c.wrench)


def test_program_alternates_on_its_axis_within_the_amplitude():
    config = jig_config()
    program = jig_program(EXPERIMENTS, config, np.random.default_rng(0))
    x_segment, y_segment = program.segments
    assert (x_segment.axis, y_segment.axis) == ("x", "y")
    inside = (program.t_s >= x_segment.t_start_s) & (program.t_s < x_segment.t_end_s)
    tau_x = program.wrench[inside, 3]
    assert tau_x.max() > 0.02 * (1 - config.amplitude_spread) * 0.99
    assert tau_x.min() < -0.02 * (1 - config.amplitude_spread) * 0.99
    assert np.abs(tau_x).max() <= 0.02 * (1 + 3 * config.crosstalk)
    # The hand's crosstalk is small next to the main axis.
    assert np.abs(program.wrench[inside, 4]).max() < 0.3 * np.abs(tau_x).max()
    # Before the experiments: no load; the grip closes after the open interval.
    before = program.t_s < x_segment.t_start_s
    assert np.all(program.wrench[before] == 0)
    assert program.grip(0.1) == 0.0
    assert program.grip(program.reference[0] + 0.01) == pytest.approx(config.grip_force_n)


def test_sampling_rates_and_jitter():
    config = jig_config()
    rng = np.random.default_rng(1)
    program = jig_program(EXPERIMENTS, config, rng)
    times = tactile_times(program, config, rng)
    periods = np.diff(times)
    assert np.all(periods > 0)
    assert np.median(periods) == pytest.approx(1 / config.tactile_rate_hz, rel=0.05)
    assert periods.std() > 0  # jittered
    ft_t, wrench = ft_samples(program, config, rng)
    assert np.diff(ft_t) == pytest.approx(1 / config.ft_rate_hz)
    noise = wrench[ft_t < config.open_s, 3]
    assert noise.std() == pytest.approx(config.ft_torque_noise_nm, rel=0.5)


def test_live_gel_carries_its_share_of_the_applied_wrench():
    config = jig_config()
    program = jig_program(EXPERIMENTS, config, np.random.default_rng(0))
    gel = JigGel(gel_model("gelsight_mini", "plate"), program, config)
    t = program.segments[0].t_start_s + 1.0
    state = gel.state(t)
    expected = config.gel_load_factor * program.applied(t)
    assert state.carried.tau_x == pytest.approx(expected[3], rel=1e-4, abs=1e-9)
    assert state.carried.fx == pytest.approx(expected[0], rel=1e-4, abs=1e-9)


def test_bad_jig_values_name_the_key():
    config = jig_config()
    with pytest.raises(ValueError, match="grip_force_n"):
        dataclasses.replace(config, grip_force_n=-1.0)
    with pytest.raises(ValueError, match="ramp_max_s"):
        dataclasses.replace(config, ramp_min_s=2.0, ramp_max_s=1.0)
    with pytest.raises(ValueError, match="axis"):
        Experiment("w", 0.01, 1)


def test_applied_interpolates_like_numpy_and_holds_beyond_the_ends():
    program = jig_program([Experiment("x", 0.04, 2)], jig_config(), np.random.default_rng(3))
    for t in (-1.0, 0.0, 0.0013, 1.234567, program.duration_s / 2, program.duration_s, 1e6):
        expected = [np.interp(t, program.t_s, column) for column in program.wrench.T]
        assert np.allclose(program.applied(t), expected, rtol=0, atol=1e-15)
