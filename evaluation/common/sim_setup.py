"""Loading the simulator's pieces by name: gel profiles, objects, the jig scene."""

from __future__ import annotations

from core.config import load_config, resolve_config_path
from drivers.sim.gel.model import GelModel
from drivers.sim.gel.profile import SHAPES, gel_profile
from drivers.sim.scenes.jig import JigConfig

SENSORS = ("gelsight_mini", "digit")


def gel_model(sensor: str, shape: str) -> GelModel:
    if shape not in SHAPES:
        raise ValueError(f"unknown object '{shape}'; expected one of {', '.join(SHAPES)}")
    return GelModel(gel_profile(sensor), SHAPES[shape])


def jig_config(name: str = "calibration_jig") -> JigConfig:
    return load_config(JigConfig, resolve_config_path(name, "scenes"))
