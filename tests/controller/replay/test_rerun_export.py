"""``replay export EP --rerun OUT.rrd`` on the suite's recorded episode, read back with
Rerun's own reader (``rerun.chunk.RrdReader``, rerun-sdk 0.41): the scalar series, texts,
images and frames are there, on the loop's timeline, with the episode's values."""

from __future__ import annotations

import sys
from collections import defaultdict

import numpy as np
import pytest

from controller.cli.replay import main
from controller.episode import read_episode

rerun_chunk = pytest.importorskip("rerun.chunk")  # the 'rerun' extra, in dev


def one_error_line(capsys) -> str:
    err = capsys.readouterr().err.strip()
    assert err.startswith("replay: error: ") and "\n" not in err and "Traceback" not in err
    return err


@pytest.fixture(scope="module")
def recording(episode_path, tmp_path_factory):
    """Entity path -> list of record batches of the recording written from the episode."""
    out = tmp_path_factory.mktemp("rerun") / "episode.rrd"
    assert main(["export", str(episode_path), "--rerun", str(out)]) == 0
    assert [p.name for p in out.parent.iterdir()] == ["episode.rrd"]  # no temporary left
    batches = defaultdict(list)
    for chunk in rerun_chunk.RrdReader(out).stream():
        batches[chunk.entity_path].append(chunk.to_record_batch())
    return batches


def column(batches, name: str) -> list:
    return [v for batch in batches for v in batch.column(name).to_pylist()]


def texts(batches) -> list[str]:
    return [one for (one,) in column(batches, "TextLog:text")]


def loop_times_s(batches) -> np.ndarray:
    return np.array([t.total_seconds() for t in column(batches, "loop_time")])


@pytest.mark.parametrize(
    "topic, field",
    [
        ("/tactile/wrench", "tau_z"),  # a torque
        ("/tactile/wrench", "fv_tau_z"),
        ("/sim/truth", "gel_wrench_s"),  # forces and torques
        ("/control/command", "twist_linear_m_s"),  # a command (absent when none was sent)
        ("/arm/status", "tcp_xyz_m"),  # the arm's state
        ("/arm/status", "tcp_rpy_rad"),
    ],
)
def test_every_number_is_a_scalar_series_with_the_episodes_values(
    recording, episode_path, topic, field
):
    episode = read_episode(episode_path)  # an absent value is None here, no point in Rerun
    messages = [m for m in episode.messages(topic) if m.value.get(field) is not None]
    assert len(messages) > 100, (topic, field)
    batches = recording[f"{topic}/{field}"]
    values = np.array(column(batches, "Scalars:scalars"), dtype=float)
    times = loop_times_s(batches)
    order = np.argsort(times, kind="stable")
    expected = np.array([np.atleast_1d(m.value[field]) for m in messages], dtype=float)
    assert values.shape == expected.shape  # the count and the components
    np.testing.assert_allclose(values[order], expected, rtol=1e-12)
    np.testing.assert_allclose(times[order], [m.t_s for m in messages], atol=1e-9)


def test_phases_transitions_images_and_frames_are_there(recording, episode_path):
    episode = read_episode(episode_path)
    transitions = [m.value for m in episode.messages("/machine/transition")]
    lines = texts(recording["/machine/transition"])
    first = transitions[0]
    rule = f" ({first['rule']})" if first["rule"] else ""
    assert lines[0] == f"{first['from']} -> {first['to']}: {first['reason']}{rule}"
    assert len(lines) == len(transitions) >= 5
    phases = texts(recording["/loop/tick/phase"])
    assert phases == [phases[0]] + [t["to"] for t in transitions][: len(phases) - 1]
    images = recording["/tactile/image"]
    assert sum(b.num_rows for b in images) == episode.counts["/tactile/image"]
    fields = recording["/tactile/field"]
    assert sum(b.num_rows for b in fields) == episode.counts["/tactile/field"]
    assert {"/frames/B/T", "/frames/B/T/S"} <= set(recording)


def test_the_output_is_never_the_input_and_must_be_rrd(episode_path, tmp_path, capsys):
    before = episode_path.stat().st_mtime_ns
    assert main(["export", str(episode_path), "--rerun", str(episode_path)]) == 2
    assert "--rerun" in one_error_line(capsys)
    assert main(["export", str(episode_path), "--rerun", str(tmp_path / "x.mcap")]) == 2
    assert "expected a .rrd file" in one_error_line(capsys)
    assert episode_path.stat().st_mtime_ns == before and list(tmp_path.iterdir()) == []


def test_without_rerun_sdk_it_is_one_line_naming_the_extra(episode_path, tmp_path, capsys,
                                                           monkeypatch):  # fmt: skip
    monkeypatch.setitem(sys.modules, "rerun", None)  # import rerun raises ImportError
    assert main(["export", str(episode_path), "--rerun", str(tmp_path / "x.rrd")]) == 2
    assert "pip install -e '.[rerun]'" in one_error_line(capsys)
    assert list(tmp_path.iterdir()) == []
