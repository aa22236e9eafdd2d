"""``replay export --lerobot``: the dataset read back with pyarrow, pandas and PyAV, and checked
against the LeRobot v3.0 layout's required keys (taken from LeRobot's own code at the
release that introduced v3.0, lerobot 0.4.0: datasets/utils.py ``create_empty_dataset_info``
and ``DEFAULT_FEATURES``, lerobot_dataset.py's episode metadata, video_utils.py
``get_video_info``, compute_stats.py) -- written out here, independently of the exporter."""

from __future__ import annotations

import json
import shutil

import av
import numpy as np
import pandas as pd
import pyarrow.compute as pc
import pyarrow.parquet as pq
import pytest

from controller.cli.replay import main
from controller.episode import read_episode
from controller.replay import episode_streams
from tests.conftest import made_once

INFO_KEYS = {
    "codebase_version", "robot_type", "total_episodes", "total_frames", "total_tasks",
    "chunks_size", "data_files_size_in_mb", "video_files_size_in_mb", "fps", "splits",
    "data_path", "video_path", "features",
}  # fmt: skip
DEFAULT_FEATURES = {
    "timestamp": "float32",
    "frame_index": "int64",
    "episode_index": "int64",
    "index": "int64",
    "task_index": "int64",
}
EPISODE_COLUMNS = {
    "episode_index", "tasks", "length", "data/chunk_index", "data/file_index",
    "dataset_from_index", "dataset_to_index", "meta/episodes/chunk_index",
    "meta/episodes/file_index",
}  # fmt: skip
VIDEO_EPISODE_COLUMNS = ("chunk_index", "file_index", "from_timestamp", "to_timestamp")
VIDEO_INFO_KEYS = {
    "video.height", "video.width", "video.codec", "video.pix_fmt", "video.is_depth_map",
    "video.fps", "video.channels", "has_audio",
}  # fmt: skip
STATS_KEYS = {"min", "max", "mean", "std", "count", "q01", "q10", "q50", "q90", "q99"}
DATA_PATH = "data/chunk-{chunk_index:03d}/file-{file_index:03d}.parquet"
VIDEO_PATH = "videos/{video_key}/chunk-{chunk_index:03d}/file-{file_index:03d}.mp4"
ARROW_TYPES = {"float32": "float", "int64": "int64"}
FPS = 25  # the GelSight Mini's


def logged_frames(episode_path) -> tuple[np.ndarray, np.ndarray]:
    """The recorded frames' push times (the tick's, s) and capture times (s), in push order:
    docs/EPISODES.md's rule makes row k of an episode its frame k."""
    logged = list(episode_streams.frames(read_episode(episode_path)))
    return np.array([f.t_s for f in logged]), np.array([f.capture_t_s for f in logged])


def sample_count(frames: int) -> int:
    """LeRobot's image-stat sample count, lerobot 0.6.1 compute_stats.estimate_num_samples
    (written out here): frames ** 0.75, at least min(100, frames), at most 10 000."""
    return max(min(100, frames), min(int(frames**0.75), 10_000))


@pytest.fixture(scope="module")
def dataset(episode_path, run_root):
    """Two episodes (the recorded one and a copy) exported into one dataset, once per test
    run (tests/conftest.py)."""

    def export(folder):
        folder.mkdir()
        second = folder / "second.mcap"
        shutil.copyfile(episode_path, second)
        root = folder / "lerobot"
        assert main(["export", str(episode_path), str(second), "--lerobot", str(root)]) == 0

    return made_once(run_root, "lerobot_export", export) / "lerobot"


def test_info_has_every_required_key_and_describes_each_feature(dataset, episode_path):
    info = json.loads((dataset / "meta" / "info.json").read_text())
    assert INFO_KEYS <= set(info)
    assert info["codebase_version"] == "v3.0"
    assert info["data_path"] == DATA_PATH and info["video_path"] == VIDEO_PATH
    frames = read_episode(episode_path).counts["/tactile/image"]
    assert info["fps"] == FPS and info["total_episodes"] == 2 and info["total_tasks"] == 1
    assert info["total_frames"] == 2 * frames and info["splits"] == {"train": "0:2"}
    features = info["features"]
    for key, dtype in DEFAULT_FEATURES.items():
        assert features[key] == {"dtype": dtype, "shape": [1], "names": None}
    for key, feature in features.items():
        assert {"dtype", "shape", "names"} <= set(feature), key
        if feature["dtype"] == "float32" and feature["names"] is not None:
            assert feature["shape"] == [len(feature["names"])], key
    video = features["observation.images.tactile"]
    assert video["dtype"] == "video" and video["shape"] == [240, 320, 3]
    assert video["names"] == ["height", "width", "channels"]
    assert VIDEO_INFO_KEYS <= set(video["info"])
    assert video["info"]["video.codec"] in ("h264", "av1") and video["info"]["video.fps"] == 25
    for key in ("observation.state", "action", "observation.state.window", "action.window"):
        assert key in features
    assert features["observation.state.window"]["shape"] == [4 * 7]  # 100 Hz ticks / 25 Hz


def test_the_data_file_holds_every_non_video_feature_with_its_dtype(dataset):
    info = json.loads((dataset / "meta" / "info.json").read_text())
    table = pq.read_table(dataset / DATA_PATH.format(chunk_index=0, file_index=0))
    expected = {k for k, f in info["features"].items() if f["dtype"] != "video"}
    assert set(table.column_names) == expected
    for key in expected:
        feature, field = info["features"][key], table.schema.field(key)
        if feature["shape"] == [1]:
            assert str(field.type) == ARROW_TYPES[feature["dtype"]], key
        else:
            assert field.type.list_size == feature["shape"][0], key
            assert str(field.type.value_type) == ARROW_TYPES[feature["dtype"]], key
    rows = table.to_pydict()
    n = len(rows["index"])
    assert rows["index"] == list(range(n)) and n == info["total_frames"]
    episodes = np.array(rows["episode_index"])
    assert set(episodes) == {0, 1} and np.all(np.diff(episodes) >= 0)
    for episode in (0, 1):
        frame_index = np.array(rows["frame_index"])[episodes == episode]
        timestamp = np.array(rows["timestamp"])[episodes == episode]
        assert list(frame_index) == list(range(len(frame_index)))
        # LeRobot's check_timestamps_sync: consecutive timestamps 1 / fps apart (1e-4 s)
        assert np.all(np.abs(np.diff(timestamp) - 1 / info["fps"]) < 1e-4)
        np.testing.assert_allclose(timestamp, frame_index / info["fps"], atol=1e-6)
    assert set(rows["task_index"]) == {0}
    assert np.isfinite(np.array(rows["observation.state"])).all()


def test_each_row_is_one_frame_with_its_capture_time_and_the_state_at_its_push(
    dataset, episode_path
):
    episode = read_episode(episode_path)
    ticks = episode_streams.ticks(episode)
    pushed, captured = logged_frames(episode_path)
    table = pq.read_table(dataset / DATA_PATH.format(chunk_index=0, file_index=0))
    first = table.filter(pc.equal(table.column("episode_index"), 0))
    assert first.num_rows == len(pushed)  # one row per frame: none dropped, none repeated
    capture = np.array(first.column("observation.tactile.capture_time_s").to_pylist())
    np.testing.assert_allclose(capture, captured - captured[0], atol=1e-5)
    nominal = np.array(first.column("timestamp").to_pylist())
    # the camera's jitter: the capture times stray from k / fps by more than LeRobot's
    # tolerance_s (1e-4 s), which is why they are a feature and not the timestamp
    assert np.abs(capture - nominal).max() > 1e-3
    state = np.array(first.column("observation.state").to_pylist())
    for row in (0, 100, len(pushed) - 1):  # the tick at or before the frame's push
        tick = int(np.flatnonzero(ticks.t_s <= pushed[row] + 1e-6)[-1])
        expected = [*ticks.tcp_xyz_m[tick], *ticks.tcp_rpy_rad[tick], ticks.gripper_width_m[tick]]
        np.testing.assert_allclose(state[row], expected, rtol=1e-6)
    estimates = episode_streams.estimates(episode)  # one per frame pushed
    np.testing.assert_array_equal(estimates.push_index, np.arange(len(pushed)))
    wrench = np.array(first.column("observation.wrench").to_pylist())
    np.testing.assert_allclose(wrench[:, 2], estimates.column("tau_z"), rtol=1e-6)
    np.testing.assert_array_equal(wrench[:, -1], ~estimates.zeroing)  # valid
    assert estimates.zeroing.sum() > 10 and (~estimates.zeroing).sum() > 150


def test_the_episodes_file_says_where_each_episodes_rows_and_frames_are(dataset):
    table = pq.read_table(dataset / "meta" / "episodes" / "chunk-000" / "file-000.parquet")
    columns = set(table.column_names)
    assert EPISODE_COLUMNS <= columns
    key = "videos/observation.images.tactile/"
    assert {key + c for c in VIDEO_EPISODE_COLUMNS} <= columns
    info = json.loads((dataset / "meta" / "info.json").read_text())
    for feature in info["features"]:
        assert {f"stats/{feature}/{s}" for s in STATS_KEYS} <= columns, feature
    rows = table.to_pylist()
    assert [r["episode_index"] for r in rows] == [0, 1]
    length = rows[0]["length"]
    assert rows[0]["dataset_from_index"] == 0 and rows[0]["dataset_to_index"] == length
    assert rows[1]["dataset_from_index"] == length
    assert rows[1]["dataset_to_index"] == length + rows[1]["length"]
    assert rows[0][key + "from_timestamp"] == 0.0
    assert rows[1][key + "from_timestamp"] == pytest.approx(length / info["fps"])
    assert rows[1][key + "to_timestamp"] == pytest.approx(2 * length / info["fps"])
    assert rows[0]["tasks"] == ["insert the usb_c plug"]


def test_tasks_read_with_pandas_as_lerobot_reads_them(dataset):
    tasks = pd.read_parquet(dataset / "meta" / "tasks.parquet")
    assert list(tasks.index) == ["insert the usb_c plug"]
    assert int(tasks.loc["insert the usb_c plug"].task_index) == 0


def test_stats_cover_every_feature_with_lerobots_shapes(dataset, episode_path):
    info = json.loads((dataset / "meta" / "info.json").read_text())
    stats = json.loads((dataset / "meta" / "stats.json").read_text())
    frames = read_episode(episode_path).counts["/tactile/image"]
    assert set(stats) == set(info["features"])
    for key, feature in info["features"].items():
        assert STATS_KEYS <= set(stats[key]), key
        if feature["dtype"] == "video":  # LeRobot's sample of each episode's frames
            assert stats[key]["count"] == [2 * sample_count(frames)]
            assert np.array(stats[key]["mean"]).shape == (3, 1, 1)
            assert 0 <= np.min(stats[key]["min"]) <= np.max(stats[key]["max"]) <= 1
        else:
            assert stats[key]["count"] == [info["total_frames"]], key
            assert np.array(stats[key]["mean"]).shape == tuple(feature["shape"])
            assert np.all(np.array(stats[key]["min"]) <= np.array(stats[key]["max"]))


def test_dataset_stats_aggregate_the_episodes_as_lerobot_does(dataset):
    """lerobot 0.6.1 aggregate_feature_stats, written out here: count-weighted mean, pooled
    variance, min of mins, max of maxs, count-weighted mean of each quantile. ``index``
    differs between the two episodes (0..n-1, then n..2n-1), so the rule shows."""
    stats = json.loads((dataset / "meta" / "stats.json").read_text())
    episodes = pq.read_table(dataset / "meta" / "episodes" / "chunk-000" / "file-000.parquet")
    rows = episodes.to_pylist()
    for key in ("index", "observation.state", "observation.images.tactile"):

        def each(name: str, key: str = key) -> np.ndarray:
            return np.array([np.array(r[f"stats/{key}/{name}"], dtype=float) for r in rows])

        counts = each("count")[:, 0]
        w = counts.reshape((-1,) + (1,) * (each("mean").ndim - 1))
        mean = (each("mean") * w).sum(axis=0) / counts.sum()
        var = ((each("std") ** 2 + (each("mean") - mean) ** 2) * w).sum(axis=0) / counts.sum()
        np.testing.assert_allclose(stats[key]["mean"], mean, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(stats[key]["std"], np.sqrt(var), rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(stats[key]["min"], each("min").min(axis=0))
        np.testing.assert_allclose(stats[key]["max"], each("max").max(axis=0))
        for q in ("q01", "q10", "q50", "q90", "q99"):
            expected = (each(q) * w).sum(axis=0) / counts.sum()
            np.testing.assert_allclose(stats[key][q], expected, rtol=1e-9, atol=1e-12)
    n = rows[0]["length"]
    assert rows[1]["length"] == n
    # index q01: the mean of 0.01 * (n - 1) and n + 0.01 * (n - 1), not the pooled 0.01 * (2n - 1)
    assert stats["index"]["q01"][0] == pytest.approx(n / 2 + 0.01 * (n - 1))
    assert stats["index"]["q01"][0] > 10 * 0.01 * (2 * n - 1)


def test_the_video_decodes_to_the_logged_frames_at_their_timestamps(dataset, episode_path):
    info = json.loads((dataset / "meta" / "info.json").read_text())
    path = dataset / VIDEO_PATH.format(
        video_key="observation.images.tactile", chunk_index=0, file_index=0
    )
    logged = [f.image()[:, :, ::-1] for f in episode_streams.frames(read_episode(episode_path))]
    with av.open(str(path)) as container:
        decoded = [
            (frame.time, frame.to_ndarray(format="rgb24")) for frame in container.decode(video=0)
        ]
    rows = len(logged)
    assert len(decoded) == info["total_frames"] == 2 * rows  # every frame, once per episode
    times = np.array([t for t, _ in decoded])
    np.testing.assert_allclose(times, np.arange(len(decoded)) / info["fps"], atol=1e-9)
    psnr = []
    for index, (_, image) in enumerate(decoded):  # row k shows frame k: none repeated
        error = image.astype(float) - logged[index % rows]
        psnr.append(10 * np.log10(255**2 / np.mean(error**2)))
    assert min(psnr) > 35, (int(np.argmin(psnr)), min(psnr))


def test_export_refuses_an_existing_folder_and_leaves_no_partial(episode_path, tmp_path, capsys):
    (tmp_path / "there").mkdir()
    assert main(["export", str(episode_path), "--lerobot", str(tmp_path / "there")]) == 2
    err = capsys.readouterr().err.strip()
    assert "already exists" in err and "\n" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["there"]


def test_episodes_at_another_loop_rate_are_one_line_naming_the_file(episode_path, tmp_path,
                                                                    capsys):  # fmt: skip
    from controller.episode.session import EPISODE_FILE, EpisodeOptions
    from controller.run import load_task
    from evaluation.trials.trial import run

    slow = tmp_path / "slow"
    task = load_task("usb_c", ["loop.rate_hz=50", "touch_spiral.timeout_s=3"])
    run(task, "dipole", 0, out_dir=slow, episode=EpisodeOptions(image_format="jpeg"))
    out = tmp_path / "dataset"
    assert main(["export", str(episode_path), str(slow / EPISODE_FILE), "--lerobot", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("replay: error: episode ") and "\n" not in err and "Traceback" not in err
    assert str(slow / EPISODE_FILE) in err and "loop 50 Hz" in err and "loop 100 Hz" in err
    assert not out.exists() and [p.name for p in tmp_path.iterdir()] == ["slow"]
