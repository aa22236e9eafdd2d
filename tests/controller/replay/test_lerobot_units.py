"""The LeRobot export's parts on made-up data: the rows at the camera's rate, the windows of
control ticks, and a dataset written whole or not at all."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest

from controller.replay.image_stats import ImageStats
from controller.replay.lerobot_alignment import (
    AlignmentError,
    camera_fps,
    frame_times,
    windows,
)
from controller.replay.lerobot_dataset import DatasetEpisode, VectorFeature, write_dataset
from controller.replay.lerobot_stats import (
    QUANTILES,
    aggregate,
    downsampled,
    numeric_stats,
    sample_count,
)


def test_every_frame_is_one_row_at_its_nominal_time_and_keeps_its_capture_time():
    captured = 1.0 + np.array([0.0, 0.04, 0.12, 0.15, 0.20, 0.24])  # 1.08 s lost, 1.15 early
    fps = camera_fps(captured)
    nominal, capture = frame_times(captured, fps)
    assert fps == 25
    np.testing.assert_allclose(nominal, [0.0, 0.04, 0.08, 0.12, 0.16, 0.20])  # none repeated
    np.testing.assert_allclose(capture, [0.0, 0.04, 0.12, 0.15, 0.20, 0.24])  # none dropped


def test_one_frame_is_too_few_to_tell_the_rate():
    with pytest.raises(AlignmentError, match="1 tactile frame"):
        camera_fps(np.array([3.0]))


def test_windows_look_back_for_the_state_and_ahead_for_the_actions():
    values = np.arange(10.0)[:, None] * np.array([[1.0, 10.0]])
    back = windows(values, np.array([0, 5]), 3, forward=False)
    ahead = windows(values, np.array([5, 9]), 3, forward=True)
    np.testing.assert_array_equal(back[0], [0, 0, 0, 0, 0, 0])  # clipped at the start
    np.testing.assert_array_equal(back[1], [3, 30, 4, 40, 5, 50])
    np.testing.assert_array_equal(ahead[0], [5, 50, 6, 60, 7, 70])
    np.testing.assert_array_equal(ahead[1], [9, 90, 9, 90, 9, 90])  # clipped at the end


def _episode(n: int, shape=(8, 16, 3), bad_frame: int | None = None) -> DatasetEpisode:
    def frames():
        for i in range(n):
            yield np.zeros((4, 4, 3) if i == bad_frame else shape, np.uint8) + i

    state = VectorFeature("observation.state", ("x_m", "y_m"), np.ones((n, 2)))
    return DatasetEpisode("task", n, frames(), (state,))


def test_a_bad_frame_leaves_no_dataset_and_no_partial_folder(tmp_path):
    root = tmp_path / "dataset"
    with pytest.raises(ValueError, match="episode 1, frame 3"):
        write_dataset([_episode(5), _episode(5, bad_frame=3)], root, 25, (8, 16))
    assert list(tmp_path.iterdir()) == []


def test_a_generator_shorter_than_the_episode_is_refused(tmp_path):
    short = DatasetEpisode("task", 6, iter([np.zeros((8, 16, 3), np.uint8)] * 4), ())
    with pytest.raises(ValueError, match="4 frames for a length of 6"):
        write_dataset([short], tmp_path / "d", 25, (8, 16))
    assert list(tmp_path.iterdir()) == []


def test_episodes_must_share_their_features(tmp_path):
    with pytest.raises(ValueError, match="differ from episode 0"):
        other = DatasetEpisode("task", 3, iter(()), ())
        write_dataset([_episode(3), other], tmp_path / "d", 25, (8, 16))
    assert list(tmp_path.iterdir()) == []


def test_image_statistics_stream_in_histograms_and_match_numpys_on_the_pixels():
    rng = np.random.default_rng(3)
    frames = [rng.integers(0, 256, (12, 20, 3), dtype=np.uint8) for _ in range(7)]
    frames[2][:] = 17  # a constant frame: repeated values
    stats = ImageStats()
    for frame in frames[:4]:
        stats.add(frame)
    rest = ImageStats()
    for frame in frames[4:]:
        rest.add(frame)
    stats.merge(rest)
    got = stats.stats()
    pixels = np.stack(frames).reshape(-1, 3) / 255.0
    expected = {
        "min": pixels.min(axis=0), "max": pixels.max(axis=0), "mean": pixels.mean(axis=0),
        "std": pixels.std(axis=0),
    }  # fmt: skip
    for q in QUANTILES:
        expected[f"q{round(q * 100):02d}"] = np.quantile(pixels, q, axis=0)
    for key, value in expected.items():
        np.testing.assert_allclose(got[key].reshape(3), value, rtol=0, atol=1e-12, err_msg=key)
    assert got["count"].tolist() == [7] and stats.counts.nbytes == 3 * 256 * 8


def test_episode_statistics_aggregate_as_lerobots_by_hand():
    """Episodes [0, 2] and [3, 5, 3, 5]: means 1 and 4, std 1 each, counts 2 and 4."""
    first = numeric_stats(np.array([[0.0], [2.0]]))
    second = numeric_stats(np.array([[3.0], [5.0], [3.0], [5.0]]))
    got = aggregate([first, second])
    assert got["count"].tolist() == [6]
    assert got["min"].tolist() == [0.0] and got["max"].tolist() == [5.0]
    np.testing.assert_allclose(got["mean"], [(2 * 1 + 4 * 4) / 6])  # 3
    # pooled: (2 * (1 + (1 - 3)^2) + 4 * (1 + (4 - 3)^2)) / 6 = 3, the rows' own variance
    np.testing.assert_allclose(got["std"], [np.sqrt(3.0)])
    np.testing.assert_allclose(np.var([0, 2, 3, 5, 3, 5]), 3.0)
    # quantiles: the count-weighted mean of the episodes', not the pooled rows' quantile
    np.testing.assert_allclose(got["q50"], [(2 * 1.0 + 4 * 4.0) / 6])  # 3
    np.testing.assert_allclose(got["q01"], [(2 * 0.02 + 4 * 3.0) / 6])  # 2.0067, pooled 0.05


def test_image_statistics_sample_frames_as_lerobot_does():
    # lerobot's estimate_num_samples docstring: 1000 -> 177, 2000 -> 299, 5000 -> 594
    assert [sample_count(n) for n in (1000, 2000, 5000, 20000)] == [177, 299, 594, 1681]
    assert sample_count(50) == 50 and sample_count(300) == 100 and sample_count(10**6) == 10_000
    assert downsampled(np.zeros((240, 320, 3))).shape == (120, 160, 3)  # 320 // 150 = 2
    assert downsampled(np.zeros((240, 299, 3))).shape == (240, 299, 3)


def test_a_feature_needs_a_row_per_frame_and_a_name_per_column():
    with pytest.raises(ValueError, match=r"shape \(frames, 2\)"):
        VectorFeature("action", ("a", "b"), np.ones((4, 3)))
    with pytest.raises(ValueError, match="3 rows for 4 frames"):
        DatasetEpisode("task", 4, iter(()), (VectorFeature("action", ("a",), np.ones((3, 1))),))


def test_many_episodes_are_written_in_bounded_memory(tmp_path):
    """Episodes are taken one at a time and only their numeric rows kept: the Python-side
    peak does not grow with the episodes (the sampled frames as float64 did: 20 episodes of
    100 frames of 96 x 128 would have held 590 MB)."""

    def episodes(count: int):
        for _ in range(count):
            yield _episode(100, shape=(96, 128, 3))

    peaks = []
    for count in (2, 20):
        tracemalloc.start()
        write_dataset(episodes(count), tmp_path / f"d{count}", 25, (96, 128))
        peaks.append(tracemalloc.get_traced_memory()[1])
        tracemalloc.stop()
    assert peaks[1] < peaks[0] + 8 * 2**20, peaks  # not 18 episodes' frames more
