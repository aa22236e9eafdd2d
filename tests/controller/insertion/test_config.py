"""The machine's configuration: the example task sections load; bad values give one line."""

import dataclasses

import numpy as np
import pytest
import yaml

from controller.insertion.machine_config import (
    ApproachSettings,
    MachineConfig,
    SignalSettings,
    s2t_matrix,
)
from controller.run.task import load_task
from core.config import CONFIG_ROOT, ConfigError, load_yaml_extending

EXAMPLE = CONFIG_ROOT / "tasks" / "usb_c.yaml"


def example() -> dict:
    return load_yaml_extending(EXAMPLE)


def load_edited(data: dict, folder) -> object:
    """The task config of ``data`` written as a task file in ``folder`` (real backend: the
    scene is not read)."""
    path = folder / "task.yaml"
    path.write_text(yaml.safe_dump(data))
    return load_task(str(path), backend="real").config


def test_the_example_loads_and_matches_the_code_defaults():
    machine = load_task(str(EXAMPLE)).config.machine
    defaults = MachineConfig()
    for part in dataclasses.fields(MachineConfig):
        mine, theirs = getattr(machine, part.name), getattr(defaults, part.name)
        for key in dataclasses.fields(type(mine)):
            a, b = getattr(mine, key.name), getattr(theirs, key.name)
            assert a == pytest.approx(b, rel=1e-3) if isinstance(a, float) else a == b, key.name


@pytest.mark.parametrize(
    ("where", "value", "expected"),
    [
        (
            "machine.search.pattern",
            "zigzag",
            "key 'machine.search.pattern': expected one of 'spiral', 'raster', got 'zigzag'",
        ),
        (
            "machine.approach.contact_frames",
            0,
            "key 'machine.approach.contact_frames': expected an integer in [1, 100], got 0",
        ),
        (
            "machine.slip.policy",
            "retry",
            "key 'machine.slip.policy': expected one of 'regrasp', 'fail', got 'retry'",
        ),
        (
            "plug.length_m",
            -0.01,
            "key 'plug.length_m': expected a number in [0.005, 0.1], got -0.01",
        ),
        (
            "machine.signals.torque_axes",
            ["+x", "+x", "-y"],
            "key 'machine.signals.torque_axes': expected each tool axis once",
        ),
        ("machine.signals.torque_axes", ["+x", "+z", "+y"], "right-handed frame"),
        (
            "machine.insert.force_budget",
            9.0,
            "key 'machine.insert.force_budget': expected at most limits.force_limit (5.33)",
        ),
        (
            "machine.approach.tilt_rad",
            0.6,
            "key 'machine.approach.tilt_rad': expected less than limits.tilt_limit_rad",
        ),
        ("machine.search.pitch_m", True, "key 'machine.search.pitch_m': expected a number"),
    ],
)
def test_bad_values_give_one_line_naming_the_file_and_key(where, value, expected, tmp_path):
    data = example()
    *parents, key = where.split(".")
    node = data
    for name in parents:
        node = node[name]
    node[key] = value
    with pytest.raises(ConfigError) as error:
        load_edited(data, tmp_path)
    message = str(error.value)
    assert message.startswith(f"{tmp_path / 'task.yaml'}: ")
    assert expected in message and "\n" not in message


def test_unknown_and_missing_keys(tmp_path):
    data = example()
    data["machine"]["search"]["spiral_turns"] = 3
    with pytest.raises(ConfigError, match="unknown key 'machine.search.spiral_turns'"):
        load_edited(data, tmp_path)
    data = example()
    del data["machine"]["timeouts"]["total_s"]
    with pytest.raises(ConfigError, match="missing key 'machine.timeouts.total_s'"):
        load_edited(data, tmp_path)
    data = example()
    del data["hole"]
    with pytest.raises(ConfigError, match="task.yaml: missing key 'hole'"):
        load_edited(data, tmp_path)


def test_cross_field_rules_apply_in_code_too():
    with pytest.raises(ValueError, match="key 'approach.tilt_rad'"):
        MachineConfig(approach=ApproachSettings(tilt_rad=0.6)).limits  # noqa: B018
    with pytest.raises(ValueError, match="key 'search.contact_lost_sigma'"):
        from controller.insertion.machine_config import SearchSettings

        MachineConfig(search=SearchSettings(contact_lost_sigma=9.0))
    with pytest.raises(ValueError, match="key 'torque_axes'"):
        SignalSettings(torque_axes=("+x", "+y", "+y"))


def test_s2t_matrix_default_mapping():
    r = s2t_matrix(("+x", "+z", "-y"))
    np.testing.assert_array_equal(r @ [1, 0, 0], [1, 0, 0])  # S x (image columns) = T x
    np.testing.assert_array_equal(r @ [0, 1, 0], [0, 0, 1])  # S y (image rows) = T z
    np.testing.assert_array_equal(r @ [0, 0, 1], [0, -1, 0])  # S z (camera axis) = -T y
    assert np.linalg.det(r) == pytest.approx(1.0)


def test_the_task_file_has_the_machine_sections():
    assert {"plug", "hole", "machine"} <= set(load_yaml_extending(EXAMPLE))
