"""A sensor's geometry has one source, its profile (configs/sensors/NAME.yaml).

The gel YAML does not repeat it (``gel_profile`` takes it from the profile), the twin prints
its markers at the profile's pitch, and the camera YAML, which must ask the camera for the
very image the profile describes, agrees with it key by key.
"""

from __future__ import annotations

import pytest
import yaml

from core.config import CONFIG_ROOT, ConfigError
from core.sensor_profile import sensor_names, sensor_profile
from drivers.registry import load_device_config
from drivers.sim.gel.profile import GEOMETRY_KEYS, gel_profile

SENSORS = CONFIG_ROOT / "sensors"


def test_every_file_in_the_sensor_folder_belongs_to_a_profile():
    names = sensor_names()
    assert names == ["digit", "gelsight_mini"]
    for path in SENSORS.glob("*.yaml"):
        stem = path.stem.removesuffix("_camera").removesuffix("_gel")
        assert stem in names, path


@pytest.mark.parametrize("name", sensor_names())
def test_the_camera_file_asks_for_the_profiles_image(name):
    profile = sensor_profile(name)
    for backend in ("sim", "real"):
        camera = load_device_config(SENSORS / f"{name}_camera.yaml", backend).config
        assert camera.model == camera.name == profile.name
        out = (camera.output_width_px, camera.output_height_px)
        if camera.model == "digit":
            out = out[::-1]  # the DIGIT image is turned after the resize
        assert out == (profile.width_px, profile.height_px)
        assert camera.frame_rate_hz == profile.fps_hz


@pytest.mark.parametrize("name", sensor_names())
def test_the_twin_prints_the_profiles_markers(name):
    profile = sensor_profile(name)
    twin = load_device_config(SENSORS / f"{name}_camera.yaml", "sim").config
    assert twin.marker_pitch_px == profile.marker_pitch_px
    if profile.marker_pitch_mm is None:
        assert twin.marker_pitch_px is None and twin.sim.marker_radius_px is None
    else:
        assert twin.marker_pitch_px == pytest.approx(profile.marker_pitch_mm / profile.mm_per_px)


def test_the_mini_marker_pitch_is_2_mm_at_its_scale():
    assert sensor_profile("gelsight_mini").marker_pitch_px == pytest.approx(2.0 / 0.0634)


@pytest.mark.parametrize("name", sensor_names())
def test_the_gel_takes_its_image_from_the_profile(name):
    text = yaml.safe_load((SENSORS / f"{name}_gel.yaml").read_text())
    assert not set(GEOMETRY_KEYS) & set(text)
    gel, profile = gel_profile(name), sensor_profile(name)
    assert gel.name == profile.name
    for key in GEOMETRY_KEYS:
        assert getattr(gel, key) == getattr(profile, key)


def test_a_gel_file_that_repeats_the_geometry_or_names_no_sensor_is_refused(tmp_path):
    text = (SENSORS / "digit_gel.yaml").read_text()
    repeated = tmp_path / "repeated_gel.yaml"
    repeated.write_text(text + "mm_per_px: 0.0645\n")
    with pytest.raises(ConfigError, match=r"repeated_gel\.yaml: key 'mm_per_px' comes from"):
        gel_profile(str(repeated))
    unknown = tmp_path / "unknown_gel.yaml"
    unknown.write_text(text.replace("name: digit", "name: nope"))
    with pytest.raises(ConfigError, match=r"unknown_gel\.yaml: key 'name': expected the name"):
        gel_profile(str(unknown))
    with pytest.raises(ConfigError, match="unknown sensor configuration 'nope'"):
        gel_profile("nope")


def test_a_twin_marker_radius_must_fit_the_profiles_markers(tmp_path):
    data = yaml.safe_load((SENSORS / "gelsight_mini_camera.yaml").read_text())
    for radius, message in (
        (None, "expected null for a sensor without printed markers"),
        (20.0, "expected at most half the marker pitch"),
    ):
        data["sim"]["marker_radius_px"] = radius
        path = tmp_path / "camera.yaml"
        path.write_text(yaml.safe_dump(data))
        with pytest.raises(ConfigError, match=f"key 'sim.marker_radius_px': {message}"):
            load_device_config(path)


def test_the_sensor_list_names_only_profiles():
    with pytest.raises(ConfigError) as info:
        sensor_profile("nope")
    assert str(info.value).startswith("unknown sensor configuration 'nope'; expected one of: ")
    assert "digit, gelsight_mini (or a path" in str(info.value)
    assert "_camera" not in str(info.value) and "_gel" not in str(info.value)
    with pytest.raises(ConfigError, match="unknown sensor configuration 'digit_gel'"):
        sensor_profile("digit_gel")
