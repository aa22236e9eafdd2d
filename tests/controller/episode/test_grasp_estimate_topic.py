"""``/machine/grasp_estimate``: the machine's in-hand estimates (FEEL's and the grasp's
imprint's) in the episode, as the machine made them, read back by
``episode_streams.grasp_estimates``; a run whose FEEL never ran has the imprint's only."""

from __future__ import annotations

import json

import numpy as np
import pytest

from controller.episode import read_episode
from controller.episode.session import EPISODE_FILE
from controller.episode.topics import GRASP_ESTIMATE, JSON_SCHEMAS
from controller.replay.episode_streams import grasp_estimates, transitions


def test_feels_estimates_round_trip_with_the_trials_record(felt_trial):
    episode = read_episode(felt_trial / EPISODE_FILE)
    result = json.loads((felt_trial / "trial.json").read_text())["result"]
    estimates = grasp_estimates(episode)
    assert estimates and episode.counts[GRASP_ESTIMATE.name] == len(estimates)
    assert {(e.plane, e.method) for e in estimates} == {
        ("thickness", "rock"),
        ("width", "rock"),
        ("width", "imprint"),
    }
    (imprint,) = [e for e in estimates if e.method == "imprint"]  # the grasp's, before FEEL
    assert imprint.kept and np.isnan(imprint.tilt_rad)
    assert imprint.tip_offset_m == pytest.approx(result["imprint_offset_est_m"], abs=1e-15)
    estimates = [e for e in estimates if e.method == "rock"]
    # each plane's last is its kept one: the trial's tilt estimate and the tip offset it implies
    for plane, tilt, tip in (
        ("thickness", "grasp_tilt_thickness_est_rad", "tip_y_est_m"),
        ("width", "grasp_tilt_est_rad", "tip_x_est_m"),
    ):
        in_plane = [e for e in estimates if e.plane == plane]
        kept = [e for e in in_plane if e.kept]
        assert kept == in_plane[-1:]
        assert kept[0].tilt_rad == result[tilt]
        assert kept[0].tip_offset_m == pytest.approx(result[tip], abs=1e-15)
    # made in FEEL: between the touch and the felt transition
    changes = {t.reason: t.t_s for t in transitions(episode)}
    assert all(changes["touched"] < e.t_s < changes["felt"] for e in estimates)
    # the messages as written: the schema's fields, valid against it (the imprint: no tilt)
    schema = JSON_SCHEMAS[GRASP_ESTIMATE.schema]
    types = {"number": (int, float), "string": (str,), "boolean": (bool,)}
    for message in episode.messages(GRASP_ESTIMATE.name):
        assert set(message.value) == set(schema["properties"])
        for name, value in message.value.items():
            if name == "tilt_rad" and message.value["method"] == "imprint":
                assert value is None  # absent from the message: the imprint finds no tilt
                continue
            field = schema["properties"][name]
            assert isinstance(value, types[field["type"]]), (name, value)
            assert value in field.get("enum", [value])
        assert message.t_s == pytest.approx(message.value["t_s"], abs=1e-9)  # log time: ns


def test_a_run_whose_feel_never_ran_has_the_imprints_only(recorded_trial):
    episode = read_episode(recorded_trial / EPISODE_FILE)
    # the first pass caught: FEEL never ran
    assert [e.method for e in grasp_estimates(episode)] == ["imprint"]
