"""The scene's measurement tools (evaluation/scene/): the search windows and torques read
from a trial's truth, and the camera effects against the real captures."""

from __future__ import annotations

import numpy as np
import pytest

from controller.insertion import Phase
from controller.insertion.interface import Transition
from evaluation.scene.search_torques import main as search_torques_main
from evaluation.scene.search_torques import search_torques_nmm, search_windows
from evaluation.scene.sensor_levels import rows


def test_search_windows_and_their_torques_relative_to_the_start():
    changes = [
        Transition(1.0, Phase.APPROACH, Phase.SEARCH, "surface_contact"),
        Transition(2.0, Phase.SEARCH, Phase.ALIGN, "hole_found"),
        Transition(3.0, Phase.ALIGN, Phase.SEARCH, "search_again"),
    ]
    windows = search_windows(changes, end_s=4.0)
    assert windows == [(1.0, 2.0), (3.0, 4.0)]
    t = np.arange(0.0, 4.01, 0.5)
    wrench = np.zeros((len(t), 6))
    wrench[:, 3] = 1e-3 * t  # tau_x grows 1 N*mm per s
    torques = search_torques_nmm({"t_s": t, "gel_wrench_s": wrench}, windows)
    assert torques[:, 0] == pytest.approx([0.0, 0.5, 1.0, 0.0, 0.5, 1.0])
    assert np.all(torques[:, 1:] == 0.0)


def test_a_bad_stiffness_list_is_a_usage_error(capsys):
    with pytest.raises(SystemExit) as stopped:
        search_torques_main(["--stiffness", "5,soft"])
    assert stopped.value.code == 2
    assert "--stiffness" in capsys.readouterr().err


def test_blur_widens_the_rendered_marker_edges_past_the_captures():
    table = rows([0.0, 0.5])
    edge = {line.split("|")[1].strip(): float(line.split("|")[2]) for line in table[2:]}
    captures = [edge["gelsight_markers_a"], edge["gelsight_markers_b"]]
    assert min(captures) - 0.05 < edge["realistic, blur 0 px"] < max(captures) + 0.05
    assert edge["realistic, blur 0.5 px"] > max(captures) + 0.2
