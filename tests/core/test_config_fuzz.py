"""Fuzzing the configuration loader: whatever a file holds, the only error is a one-line
ConfigError that names the file (never a traceback of some other type)."""

from __future__ import annotations

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from controller.tactile.settings import estimator_config
from core.config import CONFIG_ROOT, ConfigError, load_config
from core.sensor_profile import sensor_profile
from drivers.sim.gel.profile import gel_profile
from drivers.sim.twins.arm import SimArmConfig
from drivers.sim.twins.gripper import SimGripperConfig


def _device_keys(relative: str) -> dict:
    data = yaml.safe_load((CONFIG_ROOT / relative).read_text())
    return {k: v for k, v in data.items() if k not in ("type", "backend")}


LOADERS = {
    "sensor profile": (sensor_profile, CONFIG_ROOT / "sensors" / "gelsight_mini.yaml"),
    "estimator": (estimator_config, CONFIG_ROOT / "estimators" / "default.yaml"),
    "gel": (gel_profile, CONFIG_ROOT / "sensors" / "digit_gel.yaml"),
    "arm": (lambda p: load_config(SimArmConfig, p), "robot/xarm6.yaml"),
    "gripper": (lambda p: load_config(SimGripperConfig, p), "gripper/hande.yaml"),
}
SEEDS = {
    name: _device_keys(seed) if isinstance(seed, str) else yaml.safe_load(seed.read_text())
    for name, (_, seed) in LOADERS.items()
}
FUZZ = settings(
    max_examples=120,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow],
)

scalars = (
    st.none()
    | st.booleans()
    | st.integers(-(10**30), 10**30)
    | st.floats(allow_nan=True, allow_infinity=True)
    | st.text(max_size=12)
    | st.sampled_from(["serial", "dis", "gelsight_mini", "default", "x", "1.5", "yes", "~"])
)
trees = st.recursive(
    scalars,
    lambda inner: (
        st.lists(inner, max_size=4)
        | st.dictionaries(st.text(max_size=8) | st.integers(-5, 5), inner, max_size=4)
    ),
    max_leaves=12,
)


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    return tmp_path_factory.mktemp("fuzz")


def _loads_or_config_error(name: str, path, content: bytes) -> None:
    path.write_bytes(content)
    load, _ = LOADERS[name]
    try:
        load(str(path))
    except ConfigError as error:
        message = str(error)
        assert str(path) in message, message
        assert "\n" not in message, message


def _mutated(seed: dict, path: list, action: str, value) -> dict:
    """``seed`` with the key at ``path`` replaced by ``value``, deleted, or given a sibling."""
    data = yaml.safe_load(yaml.safe_dump(seed))  # a deep copy
    node = data
    for key in path[:-1]:
        node = node[key]
    if action == "replace":
        node[path[-1]] = value
    elif action == "delete":
        del node[path[-1]]
    else:
        node["extra_key"] = value
    return data


def _key_paths(node, prefix=()):
    for key, value in node.items():
        yield [*prefix, key]
        if isinstance(value, dict):
            yield from _key_paths(value, (*prefix, key))


@st.composite
def mutations(draw):
    name = draw(st.sampled_from(sorted(LOADERS)))
    seed = SEEDS[name]
    path = draw(st.sampled_from(list(_key_paths(seed))))
    action = draw(st.sampled_from(["replace", "replace", "delete", "add"]))
    return name, _mutated(seed, path, action, draw(trees))


@FUZZ
@given(mutations())
def test_mutated_real_configs_load_or_give_a_config_error(folder, case):
    name, data = case
    _loads_or_config_error(name, folder / "mutated.yaml", yaml.safe_dump(data).encode())


@FUZZ
@given(st.sampled_from(sorted(LOADERS)), trees)
def test_random_yaml_documents_give_a_config_error(folder, name, document):
    content = yaml.safe_dump(document, allow_unicode=True).encode()
    _loads_or_config_error(name, folder / "random.yaml", content)


yaml_ish = st.text(
    alphabet=" \t\n:-?[]{},&*!|>'\"%@`#.0123456789abexyz_\x00\x07\ufeff",
    max_size=80,
)


@FUZZ
@given(st.sampled_from(sorted(LOADERS)), st.binary(max_size=120) | yaml_ish.map(str.encode))
def test_random_bytes_give_a_config_error(folder, name, content):
    _loads_or_config_error(name, folder / "bytes.yaml", content)


def test_the_unmutated_seeds_load(folder):
    """The mutations start from valid files, so they reach the checks of every key."""
    for name, (load, _) in LOADERS.items():
        path = folder / f"{name}.yaml"
        path.write_text(yaml.safe_dump(SEEDS[name]))
        assert load(str(path)) is not None
