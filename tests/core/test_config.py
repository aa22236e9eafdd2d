import dataclasses
import importlib
import math
import pkgutil
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import pytest
import yaml

import core.config as config_module
from controller.tactile.settings import EstimatorConfig, estimator_config, sensor_estimator
from core.config import (
    Config,
    ConfigError,
    apply_overrides,
    build,
    config_dataclass,
    load_config,
    load_yaml,
    number,
)
from core.sensor_profile import SensorProfile, sensor_profile
from drivers.gripper.hande import HandEConfig
from drivers.registry import load_device_config
from drivers.sim.scenes.jig import JigConfig

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
    assert (sensor_estimator(mini)[0], sensor_estimator(digit)[0]) == ("default", "default")
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


@config_dataclass
class Gains(Config):
    kp: float = number(0, 10)


@config_dataclass
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


# -- one mechanism: the same declarations checked from YAML and in code ----------------


@config_dataclass
class Knobs(Config):
    count: int = number(1, 100)
    slope: float = number(-1.0, 1.0)
    unbounded: float
    mode: Literal["fast", "slow"]
    baud: Literal[9600, 115200]
    enabled: bool
    label: str
    gain: Gains | None
    rgb: tuple[float, float, float] = number(0.0, 1.0)
    weights: Mapping[str, float] = number(0.0, 10.0)


GOOD_KNOBS = {
    "count": 3,
    "slope": 0.5,
    "unbounded": -1e9,
    "mode": "fast",
    "baud": 9600,
    "enabled": False,
    "label": "x",
    "gain": {"kp": 2},
    "rgb": [0.1, 0.2, 0.3],
    "weights": {"a": 1},
}


def knobs_in_code(**change):
    values = {**GOOD_KNOBS, "gain": Gains(2), **change}
    return Knobs(**values)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"slope": True}, "key 'slope': expected a number in [-1.0, 1.0], got True"),
        ({"count": True}, "key 'count': expected an integer in [1, 100], got True"),
        ({"count": 1.5}, "key 'count': expected an integer in [1, 100], got 1.5"),
        ({"count": 2.0}, "key 'count': expected an integer in [1, 100], got 2.0"),
        ({"count": 0}, "key 'count': expected an integer in [1, 100], got 0"),
        ({"count": "3"}, "key 'count': expected an integer in [1, 100], got '3'"),
        ({"slope": math.nan}, "key 'slope': expected a number in [-1.0, 1.0], got nan"),
        ({"unbounded": math.inf}, "key 'unbounded': expected a finite number, got inf"),
        ({"unbounded": 10**400}, "key 'unbounded': expected a finite number, got 1000"),
        ({"mode": "medium"}, "key 'mode': expected one of 'fast', 'slow', got 'medium'"),
        ({"baud": True}, "key 'baud': expected one of 9600, 115200, got True"),
        ({"baud": 9600.0}, "key 'baud': expected one of 9600, 115200, got 9600.0"),
        ({"enabled": 1}, "key 'enabled': expected true or false, got 1"),
        ({"label": ""}, "key 'label': expected a non-empty string, got ''"),
        ({"label": 5}, "key 'label': expected a non-empty string, got 5"),
        ({"rgb": (0.1, 0.2)}, "key 'rgb': expected 3 items, got (0.1, 0.2)"),
        ({"rgb": (0.1, 0.2, 1.5)}, "key 'rgb[2]': expected a number in [0.0, 1.0], got 1.5"),
        ({"weights": {"a": -1}}, "key 'weights.a': expected a number in [0.0, 10.0], got -1"),
        ({"weights": {"": 1}}, "key 'weights': expected string keys, got ''"),
    ],
)
def test_one_declaration_checks_code_and_files_alike(change, message):
    with pytest.raises(ValueError) as in_code:
        knobs_in_code(**change)
    assert str(in_code.value).startswith(message)
    with pytest.raises(ConfigError) as from_file:
        build(Knobs, {**GOOD_KNOBS, **change}, source="k.yaml")
    assert str(from_file.value).startswith(f"k.yaml: {message}")


def test_nested_classes_are_checked_in_code_and_built_from_files():
    with pytest.raises(ValueError, match=r"key 'gain': expected a Gains, got \{'kp': 2\}"):
        knobs_in_code(gain={"kp": 2})
    with pytest.raises(ConfigError, match=r"k.yaml: key 'gain': expected a mapping, got 3"):
        build(Knobs, {**GOOD_KNOBS, "gain": 3}, source="k.yaml")
    with pytest.raises(ConfigError, match=r"k.yaml: key 'gain.kp': expected a number"):
        build(Knobs, {**GOOD_KNOBS, "gain": {"kp": 11}}, source="k.yaml")
    assert build(Knobs, {**GOOD_KNOBS, "gain": None}, source="k.yaml").gain is None


def test_values_are_normalised_and_frozen():
    built = build(Knobs, GOOD_KNOBS, source="k.yaml")
    assert built == knobs_in_code()
    assert type(built.slope) is float and type(knobs_in_code(slope=1).slope) is float
    assert built.rgb == (0.1, 0.2, 0.3) and isinstance(built.rgb, tuple)
    assert type(built.weights["a"]) is float
    with pytest.raises(TypeError):
        built.weights["b"] = 1.0  # type: ignore[index]
    assert built.gain == Gains(2.0)


def test_a_bad_value_in_a_driver_config_names_the_key_in_code_too():
    with pytest.raises(ValueError, match=r"key 'timeout_s': expected a number in \[0.005, 5.0\]"):
        HandEConfig(timeout_s=9)
    with pytest.raises(ValueError, match=r"key 'retries': expected an integer in \[0, 10\]"):
        HandEConfig(retries=True)
    with pytest.raises(ValueError, match=r"key 'baudrate': expected one of 9600"):
        HandEConfig(baudrate=True)


def test_a_yaml_true_is_never_a_number(tmp_path):
    data = yaml.safe_load((CONFIGS / "scenes" / "calibration_jig.yaml").read_text())
    path = tmp_path / "jig.yaml"
    path.write_text(yaml.safe_dump({**data, "gel_load_factor": True}))
    with pytest.raises(ConfigError) as info:
        load_config(JigConfig, path)
    assert str(info.value) == (
        f"{path}: key 'gel_load_factor': expected a number in [-1.0, 1.0], got True"
    )


def test_cross_field_rules_run_after_the_field_checks():
    # a wrong type is reported by the field check, never as a TypeError of a later rule
    with pytest.raises(ValueError, match=r"key 'closed_count': expected an integer"):
        HandEConfig(closed_count="255")
    with pytest.raises(ValueError, match="key 'closed_count': expected more than open_count"):
        HandEConfig(open_count=10, closed_count=10)


def test_subclass_rules_and_checks_run_once_each(monkeypatch):
    calls = []
    real = config_module._check_fields
    monkeypatch.setattr(config_module, "_check_fields", lambda c: calls.append(c) or real(c))
    twin = load_device_config(CONFIGS / "gripper" / "hande.yaml").config
    assert calls == [twin.sim, twin]
    with pytest.raises(ValueError, match="key 'sim.start_width_m'"):  # the subclass's rule
        dataclasses.replace(twin, stroke_m=0.01)
    with pytest.raises(ValueError, match="key 'closed_count'"):  # the base class's rule
        dataclasses.replace(twin, open_count=200, closed_count=100)


def test_every_declared_range_sits_on_a_config_class():
    """A ``number()`` field on a plain dataclass would never be checked."""
    unchecked = []
    for package in ("controller", "drivers", "evaluation"):
        root = importlib.import_module(package)
        for info in pkgutil.walk_packages(root.__path__, f"{package}."):
            module = importlib.import_module(info.name)
            for obj in vars(module).values():
                if not (isinstance(obj, type) and dataclasses.is_dataclass(obj)):
                    continue
                if issubclass(obj, Config):
                    continue
                if any("range" in f.metadata for f in dataclasses.fields(obj)):
                    unchecked.append(f"{obj.__module__}.{obj.__qualname__}")
    assert not unchecked


def test_build_refuses_a_class_that_does_not_check_itself():
    @dataclass(frozen=True)
    class Plain:
        kp: float = number(0, 10)

    with pytest.raises(TypeError, match="not a Config dataclass"):
        build(Plain, {"kp": 1}, source="p.yaml")


# -- the loader: any file gives a ConfigError naming it ---------------------------------


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"\xff\xfe\x00b\x00i\x00n", r"not a UTF-8 text file \(byte 0xff at offset 0\)"),
        (b"", "empty configuration file; expected a mapping of keys"),
        (b"# only a comment\n", "empty configuration file"),
        (b"- 1\n- 2\n", r"expected a mapping of keys at the top level, got \[1, 2\]"),
        (b"just text\n", "expected a mapping of keys at the top level, got 'just text'"),
        (b"name: [unclosed\n", "line 2, column 1: not valid YAML: expected ',' or ']'"),
        (b"a: 1\nb:\n  c: 2\n c: 3\n", "line 4, column 2: not valid YAML"),
        (b"a: 1\na: 2\n", "line 2, column 1: not valid YAML: key 'a' given twice"),
        (b'a: "\x07"\n', r"line 1, column 5: not valid YAML: unacceptable character #x0007"),
        (b"a: 2020-13-45\n", r"not valid YAML \(month must be in 1..12\)"),
        (b"a: !!python/object:os.system x\n", "line 1, column 4: not valid YAML"),
    ],
)
def test_unreadable_files_give_one_line_naming_the_file(tmp_path, content, message):
    path = tmp_path / "sensor.yaml"
    path.write_bytes(content)
    with pytest.raises(ConfigError, match=message) as info:
        sensor_profile(str(path))
    text = str(info.value)
    assert text.startswith(f"{path}: ") and "\n" not in text


def test_a_folder_or_a_missing_file_is_unreadable(tmp_path):
    for path in (tmp_path, tmp_path / "absent.yaml"):
        with pytest.raises(ConfigError, match=f"{path}: cannot read configuration file"):
            load_yaml(path)


def test_yaml_merge_keys_still_work(tmp_path):
    path = tmp_path / "merge.yaml"
    path.write_text("base: &b {x: 1, y: 2}\nderived:\n  <<: *b\n  y: 3\n")
    assert load_yaml(path)["derived"] == {"x": 1, "y": 3}


def test_long_values_are_cut_in_messages():
    with pytest.raises(ValueError) as info:
        knobs_in_code(label=["x" * 50] * 20)
    assert len(str(info.value)) < 150 and str(info.value).endswith("...")


def test_a_key_with_a_line_break_is_named_on_one_line(tmp_path):
    path = tmp_path / "odd.yaml"
    path.write_text('"\\n": 1\n')
    with pytest.raises(ConfigError) as info:
        load_config(SensorProfile, path)
    assert "\n" not in str(info.value) and "unknown key '\\n'" in str(info.value)


def test_a_config_holding_a_mapping_survives_pickling():
    """make evaluate sends calibrations (with a read-only ``axes`` mapping) between
    processes."""
    import pickle

    from controller.tactile.calibration import AxisFit, Calibration

    fit = AxisFit(slope=2.0, intercept=0.0, rmse=0.1, r2=0.9, samples=10)
    calibration = Calibration(sensor="gelsight_mini", estimator="default", axes={"tau_x": fit})
    again = pickle.loads(pickle.dumps(calibration))
    assert again == calibration and isinstance(again.axes, type(calibration.axes))
    with pytest.raises(TypeError):
        again.axes["tau_y"] = fit  # still read-only


# -- command-line overrides ------------------------------------------------------------


@config_dataclass
class _Scene(Config):
    friction: float = number(0.0, 2.0)
    shape: Literal["box", "round"]


@config_dataclass
class _Task(Config):
    rate_hz: float = number(1.0, 1000.0)
    scene: _Scene


_RAW = {"rate_hz": 100, "scene": {"friction": 0.3, "shape": "box"}}


def test_overrides_set_dotted_keys_with_yaml_values():
    raw = apply_overrides(_RAW, ["scene.friction=0.5", "scene.shape=round", "rate_hz=50"], "t")
    task = build(_Task, raw, source="t")
    assert task.scene.friction == 0.5 and task.scene.shape == "round" and task.rate_hz == 50.0
    assert _RAW["scene"]["friction"] == 0.3  # the input is not changed


def test_overrides_later_item_wins_and_value_is_validated_like_yaml():
    raw = apply_overrides(_RAW, ["scene.friction=0.5", "scene.friction=7"], "task.yaml")
    with pytest.raises(ConfigError, match=r"task.yaml: key 'scene.friction': expected a number"):
        build(_Task, raw, source="task.yaml")


@pytest.mark.parametrize(
    "item, message",
    [
        (
            "scene.frction=0.5",
            r"t: override 'scene.frction': unknown key 'frction' in 'scene'; "
            r"expected one of: friction, shape",
        ),
        ("speed=1", r"unknown key 'speed'; expected one of: rate_hz, scene"),
        ("rate_hz.x=1", r"key 'rate_hz' is not a mapping"),
        ("scene.friction", r"expected KEY=VALUE"),
        ("=3", r"expected KEY=VALUE"),
        ("scene..friction=3", r"expected KEY=VALUE"),
        ("scene.friction=[1", r"the value is not valid YAML"),
        ("scene.friction=" + "9" * 5000, r"not valid YAML \(Exceeds the limit"),
        ("scene.friction=2020-13-45", r"not valid YAML \(month must be in 1..12\)"),
        ("scene.friction=!!float x", r"not valid YAML \(could not convert"),
    ],
)
def test_bad_overrides_are_one_line_errors_naming_the_key(item, message):
    with pytest.raises(ConfigError, match=message) as caught:
        apply_overrides(_RAW, [item], "t")
    assert "\n" not in str(caught.value)


@pytest.mark.parametrize(
    "text, value",
    [("5e-1", 0.5), ("1e-05", 1e-05), ("1E3", 1000.0), ("1.5e3", 1500.0), ("-2e+2", -200.0)],
)
def test_a_number_with_an_exponent_is_a_number_in_overrides_and_files(tmp_path, text, value):
    """PyYAML's YAML 1.1 float needs a dot and a signed exponent; the loader reads YAML 1.2's."""
    raw = apply_overrides(_RAW, [f"scene.friction={text}"], "t")
    assert raw["scene"]["friction"] == value
    path = tmp_path / "task.yaml"
    path.write_text(f"rate_hz: 100\nscene:\n  friction: {text}\n  shape: box\n")
    assert load_yaml(path)["scene"]["friction"] == value
    assert yaml.safe_load(text) == text  # PyYAML's own safe loader is left as it was


@pytest.mark.parametrize("text", ["inf", "nan", ".inf", "-.inf", ".nan"])
def test_infinities_and_nan_stay_refused_in_overrides(text):
    raw = apply_overrides(_RAW, [f"scene.friction={text}"], "t")
    with pytest.raises(ConfigError, match=r"key 'scene.friction': expected a number"):
        build(_Task, raw, source="t")


def test_a_file_that_never_ends_is_refused_by_its_size_not_read_into_memory():
    # /dev/zero reads zeros forever: reading it whole used to exhaust the memory (the
    # offline tool's fuzz test found it with --calibration /dev/full)
    with pytest.raises(ConfigError, match=r"/dev/zero: more than 16 MiB; expected a configuration"):
        load_yaml("/dev/zero")
