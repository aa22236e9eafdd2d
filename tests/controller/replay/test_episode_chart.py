"""``replay plot`` draws the trial summary's chart from the episode: the same series as the
trial's own record (ticks.jsonl, truth.npz) of the same run."""

from __future__ import annotations

import json

import numpy as np

from controller.episode import read_episode
from controller.replay.episode_chart import episode_series, episode_title
from controller.replay.trial_chart import trial_series


def test_the_episode_gives_the_trial_records_series(episode_path):
    episode = episode_series(read_episode(episode_path))
    record = trial_series(episode_path.parent)  # the same run's ticks.jsonl and truth.npz
    np.testing.assert_array_equal(episode.tick_t_s, record.tick_t_s)
    assert list(episode.phases) == list(record.phases) and "insert" in episode.phases
    np.testing.assert_array_equal(episode.twists, record.twists)
    assert np.isfinite(episode.twists).any()
    # both hold the estimate each tick saw, at tick time (as summary.png draws them)
    np.testing.assert_array_equal(episode.estimate_t_s, record.estimate_t_s)
    np.testing.assert_array_equal(episode.torques, record.torques)
    assert episode.truth is not None and record.truth is not None
    names = ("t_s", "wrist_wrench_t", "contact_force_n", "insertion_force_n", "tip_xyz_b")
    for name in (*names, "depth_m", "hole_xy_m"):
        np.testing.assert_allclose(
            getattr(episode.truth, name), getattr(record.truth, name), err_msg=name
        )


def test_the_title_says_how_the_trial_ended_and_its_insertion_force(episode_path):
    result = json.loads((episode_path.parent / "trial.json").read_text())["result"]
    assert episode_title(read_episode(episode_path)) == (
        "usb_c seed 0 (dipole): inserted; plug insertion force max "
        f"{result['max_insertion_force_n']:.1f} N, p99 {result['p99_insertion_force_n']:.1f} N"
    )
