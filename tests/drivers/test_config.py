from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import pytest
import yaml

from controller.tactile.settings import EstimatorConfig, estimator_config, sensor_estimator
from drivers.config import Config, ConfigError, build, number
from drivers.tactile.profile import sensor_profile

CONFIGS = Path(__file__).resolve().parents[2] / "configs"


@pytest.mark.parametrize(
    "path", sorted((CONFIGS / "estimators").glob("*.yaml")), ids=lambda p: p.stem
)
def test_every_estimator_config_loads(path):
    assert isinstance(estimator_config(str(path)), EstimatorConfig)


@pytest.mark.parametrize("name", ["gelsight_mini", "digit"])
def test_sensor_profiles_load(name):
    profile = sensor_profile(name)
    assert profile.width_px == 320 and profile.height_px == 240


def test_mini_profile_scale():
    assert sensor_profile("gelsight_mini").mm_per_px == pytest.approx(0.0634)


def write_variant(tmp_path, edit):
    data = yaml.safe_load((CONFIGS / "estimators" / "default.yaml").read_text())
    edit(data)
    path = tmp_path / "variant.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


@pytest.mark.parametrize(
    "edit,message",
    [
        (
            lambda d: d.update(stride_px=2),
            r"key 'stride_px': expected a number in \[4, 160\], got 2",
        ),
        (lambda d: d.pop("ema_alpha"), "missing key 'ema_alpha'"),
        (lambda d: d.update(colour="gray"), "unknown key 'colour'"),
        (lambda d: d["flow"].update(method="lucas"), "key 'flow.method': expected one of"),
        (lambda d: d["flow"]["dis"].update(patch_size="big"), "key 'flow.dis.patch_size'"),
        (lambda d: d["flow"]["farneback"].update(poly_n=6), "key 'flow.farneback.poly_n'"),
        (lambda d: d["flow"]["markers"].update(window_px=20), "key 'flow.markers.window_px'"),
        (
            lambda d: d["flow"].update(warm_start="yes"),
            "key 'flow.warm_start': expected true or false",
        ),
        (lambda d: d.pop("slip"), "missing key 'slip'"),
        (
            lambda d: d["slip"].update(core_fraction=1.5),
            r"key 'slip.core_fraction': expected a number in \[0.0, 1.0\], got 1.5",
        ),
        (
            lambda d: d["slip"].update(gross_score=0.01),
            "key 'slip.gross_score': expected at least incipient_score",
        ),
        (lambda d: d["slip"]["rezero"].pop("quiet_s"), "missing key 'slip.rezero.quiet_s'"),
    ],
)
def test_bad_values_name_file_key_and_expectation(tmp_path, edit, message):
    path = write_variant(tmp_path, edit)
    with pytest.raises(ConfigError, match=message) as info:
        estimator_config(str(path))
    assert str(path) in str(info.value)


def test_unknown_config_name_lists_the_known_ones():
    with pytest.raises(ConfigError, match="default, .*markers"):
        estimator_config("no_such_method")


def test_each_sensor_names_its_estimator_and_markers_need_a_marker_gel(tmp_path):
    mini, digit = sensor_profile("gelsight_mini"), sensor_profile("digit")
    assert sensor_estimator(mini)[0] == sensor_estimator(digit)[0] == "default"
    assert sensor_estimator(mini, "paper") == ("paper", estimator_config("paper"))
    with pytest.raises(ConfigError, match="sensor 'digit' has none"):
        sensor_estimator(digit, "markers")
    unmarked = tmp_path / "unmarked_mini.yaml"
    data = yaml.safe_load((CONFIGS / "sensors" / "gelsight_mini.yaml").read_text())
    unmarked.write_text(yaml.safe_dump({**data, "marker_pitch_mm": None, "estimator": "markers"}))
    with pytest.raises(ConfigError, match="tracks printed markers"):
        sensor_estimator(sensor_profile(str(unmarked)))
    del data["estimator"]
    unmarked.write_text(yaml.safe_dump(data))
    with pytest.raises(ConfigError, match="estimator"):
        sensor_profile(str(unmarked))


def test_missing_and_malformed_files(tmp_path):
    with pytest.raises(ConfigError, match="cannot read"):
        sensor_profile(str(tmp_path / "absent.yaml"))
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: [unclosed\n")
    with pytest.raises(ConfigError, match="not valid YAML"):
        sensor_profile(str(bad))


@dataclass(frozen=True)
class Gains(Config):
    kp: float = number(0, 10)


@dataclass(frozen=True)
class Table(Config):
    gains: Mapping[str, Gains]


def test_mappings_of_named_entries_are_checked_entry_by_entry():
    table = build(Table, {"gains": {"x": {"kp": 1}, "y": {"kp": 2.5}}}, source="t.yaml")
    assert table.gains == {"x": Gains(1.0), "y": Gains(2.5)}
    for gains, message in [
        ({"x": {"kp": 11}}, "t.yaml: key 'gains.x.kp': expected a number in [0, 10], got 11"),
        ({"x": {}}, "t.yaml: missing key 'gains.x.kp'"),
        ({3: {"kp": 1}}, "t.yaml: key 'gains': expected string keys, got 3"),
        ([1, 2], "t.yaml: key 'gains': expected a mapping, got [1, 2]"),
    ]:
        with pytest.raises(ConfigError) as info:
            build(Table, {"gains": gains}, source="t.yaml")
        assert str(info.value) == message


def test_a_dipole_grid_that_does_not_divide_the_sensors_field_grid_is_refused(tmp_path):
    text = (CONFIGS / "estimators" / "default.yaml").read_text()
    bad = tmp_path / "bad_grid.yaml"
    bad.write_text(text.replace("{cols: 4, rows: 4}", "{cols: 5, rows: 4}"))
    message = "dipole_grid 5 x 4 must divide the estimator grid of 16 x 12 cells"
    with pytest.raises(ConfigError, match=message):
        sensor_estimator(sensor_profile("gelsight_mini"), str(bad))
