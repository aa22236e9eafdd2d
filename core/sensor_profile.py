"""Sensor profiles: the geometry of a visuotactile sensor's working image.

``configs/sensors/NAME.yaml`` is the one source of a sensor's geometry (image size, scale,
frame rate, marker pitch). The sensor's other files take it from here: the simulated gel
(``NAME_gel.yaml``, ``drivers.sim.gel.profile.gel_profile``) does not repeat it, and the
camera driver's YAML (``NAME_camera.yaml``), which must ask the camera for that very image,
is checked against it by tests/drivers/test_sensor_files.py.
"""

from __future__ import annotations

from pathlib import Path

from core.config import CONFIG_ROOT, Config, ConfigError, config_dataclass, load_config, number

FOLDER = "sensors"
COMPANION_SUFFIXES = ("_camera", "_gel")
"""Files of configs/sensors/ that belong to a profile but are not one."""


@config_dataclass
class SensorProfile(Config):
    """Geometry of a visuotactile sensor's working image (after the driver's crop/resize).

    Positions in the sensor frame S are pixels times ``mm_per_px`` from the image centre.
    ``fps_hz``: the camera's frame rate. ``marker_pitch_mm``: printed marker pitch (None: no
    markers). ``estimator``: the sensor's estimator configuration (a name in
    configs/estimators/ or a YAML path), used whenever a caller names none.
    """

    name: str
    width_px: int = number(16, 4096)
    height_px: int = number(16, 4096)
    mm_per_px: float = number(1e-4, 1.0)
    fps_hz: float = number(1, 1000)
    marker_pitch_mm: float | None = number(0.1, 20)
    estimator: str
    description: str

    @property
    def marker_pitch_px(self) -> float | None:
        """The printed marker pitch in working-image pixels (None: no markers)."""
        return None if self.marker_pitch_mm is None else self.marker_pitch_mm / self.mm_per_px


def sensor_names() -> list[str]:
    """The names of the sensor profiles in configs/sensors/."""
    stems = (path.stem for path in (CONFIG_ROOT / FOLDER).glob("*.yaml"))
    return sorted(stem for stem in stems if not stem.endswith(COMPANION_SUFFIXES))


def sensor_profile(name_or_path: str) -> SensorProfile:
    """Load a sensor profile by name (``configs/sensors/NAME.yaml``) or by YAML file path."""
    path = Path(name_or_path)
    if path.suffix not in (".yaml", ".yml"):
        if name_or_path not in sensor_names():
            raise ConfigError(
                f"unknown sensor configuration '{name_or_path}'; expected one of: "
                f"{', '.join(sensor_names())} (or a path to a .yaml file)"
            )
        path = CONFIG_ROOT / FOLDER / f"{name_or_path}.yaml"
    return load_config(SensorProfile, path)
