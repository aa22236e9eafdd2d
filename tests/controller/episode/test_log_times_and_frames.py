"""An episode's log times are the wall clock of the recording (the loop's time stays in the
messages and is what the reader gives), and ``/tf_static`` places the sensor S on the tool T
where the simulation's plug (frame S's axes, S2B) really is."""

from __future__ import annotations

import datetime

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from controller.episode import read_episode
from controller.episode.foxglove_types import loop_time_s
from controller.episode.recorder import TF_PERIOD_S, sensor_mount
from controller.episode.session import EPISODE_FILE
from controller.episode.topics import FORMAT_VERSION
from drivers.sim.scenes.insertion.frames import S_IN_T


@pytest.fixture(scope="module")
def episode(recorded_trial):
    return read_episode(recorded_trial / EPISODE_FILE)


def _rotation(q) -> Rotation:
    return Rotation.from_quat([q.x, q.y, q.z, q.w])


def test_log_times_are_the_wall_clock_and_the_reader_gives_the_loops_time(episode):
    assert episode.info["format_version"] == FORMAT_VERSION
    started = datetime.datetime.fromisoformat(episode.info["started_utc"]).timestamp()
    _, _, messages = episode.records()
    first_s = min(m.log_time for m in messages) / 1e9
    assert abs(first_s - started) < 60  # a simulated run starts its loop at 0: the start's clock
    assert episode.time_range_s()[0] == pytest.approx(0.0, abs=0.05)
    ticks = list(episode.messages("/loop/tick"))
    assert ticks and all(m.t_s == pytest.approx(m.value["start_s"], abs=1e-9) for m in ticks)
    pushes = [m.value for m in episode.messages("/tactile/push") if m.value["call"] == "push"]
    images = list(episode.messages("/tactile/image"))
    assert len(images) == len(pushes)
    for image, push in zip(images, pushes, strict=True):  # stamped on the log times' clock
        assert image.value.timestamp.seconds > 1.5e9
        assert loop_time_s(image.value.timestamp, episode.offset_ns) == pytest.approx(
            push["frame_t_s"], abs=1e-8
        )


def test_the_static_transform_puts_the_sensor_on_the_tool_where_the_plug_is(episode):
    statics = list(episode.messages("/tf_static"))
    assert statics and statics[0].t_s == next(episode.messages("/tf")).t_s
    (mount,) = statics[0].value.transforms
    assert (mount.parent_frame_id, mount.child_frame_id) == ("T", "S")
    assert np.allclose(_rotation(mount.rotation).as_matrix(), S_IN_T)
    tcp = {round(m.t_s, 6): m.value.transforms[0] for m in episode.messages("/tf")}
    angles = []
    for m in episode.messages("/sim/tf"):  # B -> T -> S against the plug's true S2B
        t = tcp.get(round(m.t_s, 6))
        plug = next(p for p in m.value.transforms if p.child_frame_id == "plug")
        if t is not None:
            s2b = _rotation(t.rotation) * _rotation(mount.rotation)
            angles.append(np.degrees((s2b.inv() * _rotation(plug.rotation)).magnitude()))
    assert len(angles) > 100 and np.median(angles) < 1.0


def test_the_mount_follows_the_torque_axes_and_the_plugs_thickness():
    origin, (x, y, z, w) = sensor_mount(("+x", "+z", "-y"), 0.0024)
    assert origin == (0.0, 0.0012, 0.0)
    assert np.allclose(Rotation.from_quat([x, y, z, w]).as_matrix(), S_IN_T)
    _, quat = sensor_mount(("-x", "-z", "-y"), 0.003)
    assert np.allclose(Rotation.from_quat(quat).as_matrix()[:, 0], [-1, 0, 0])


@pytest.mark.parametrize(("topic", "rows"), [("/tf", "/loop/tick"), ("/sim/tf", "/sim/truth")])
def test_the_transforms_come_at_every_4th_tick_or_truth_row(episode, topic, rows):
    times = np.array([m.t_s for m in episode.messages(topic)])
    every = np.array([m.t_s for m in episode.messages(rows)])
    assert times[0] == every[0] and np.all(np.isin(times, every))
    assert np.diff(times).min() >= TF_PERIOD_S and len(times) == pytest.approx(
        len(every) / 4, rel=0.05
    )
