"""Gel profiles and grasped-object shapes of the gel simulator (SI units: m, Pa, N).

A ``GelProfile`` is the simulated half of a sensor profile: the camera's working image (the
size and scale of the sensor profile ``configs/sensors/NAME.yaml``, the one source of a
sensor's geometry) plus the gel's mechanics, which live in ``configs/sensors/NAME_gel.yaml``
(``gel_profile`` joins the two); docs/SIMULATION.md explains each parameter, its default
and its source. The elastic gains are parameters on purpose: the simulator is meant
to be right about trends (where lift-off and slip begin, how the field changes shape), not
about absolute gains, which every real sensor needs a calibration for.
"""

from __future__ import annotations

from pathlib import Path
from typing import Literal

from core.config import (
    CONFIG_ROOT,
    Config,
    ConfigError,
    build,
    config_dataclass,
    load_yaml,
    number,
    show,
)
from core.sensor_profile import FOLDER, sensor_names, sensor_profile

GEL_SUFFIX = "_gel"
GEOMETRY_KEYS = ("width_px", "height_px", "mm_per_px")
"""The keys of a ``GelProfile`` that its sensor profile gives (a gel YAML may not repeat them)."""

ObjectKind = Literal["plate", "square_peg", "round_peg"]


@config_dataclass
class GelProfile(Config):
    """A sensor's gel and camera, frame S (x right, y down in the image, origin at the centre).

    Image: ``width_px`` x ``height_px`` at ``mm_per_px``; the physics grid has square cells
    of ``cell_px`` image pixels, so the image is ``width_px / cell_px`` cells wide.

    Gel: a ``gel_width_m`` x ``gel_height_m`` elastomer layer of ``thickness_m`` bonded to a
    rigid window, Young's modulus ``young_modulus_pa``, Poisson ratio ``poisson_ratio``;
    ``dome_radius_m``: the radius of curvature of a domed gel surface (``None``: flat);
    ``edge_softening_m``: length over which the pressure the layer can carry falls to zero at
    a free edge; ``friction``: Coulomb coefficient against the object.

    Camera: ``camera_distance_m`` from the pinhole to the gel surface; an indentation ``w``
    toward the camera magnifies the image about its centre by ``w / camera_distance_m``.
    """

    name: str
    width_px: int = number(16, 4096)
    height_px: int = number(16, 4096)
    mm_per_px: float = number(1e-3, 1.0)
    cell_px: int = number(1, 64)
    gel_width_m: float = number(1e-3, 0.2)
    gel_height_m: float = number(1e-3, 0.2)
    thickness_m: float = number(1e-4, 0.02)
    young_modulus_pa: float = number(1e3, 1e8)
    poisson_ratio: float = number(0.0, 0.499)
    dome_radius_m: float | None = number(1e-3, 10.0)
    edge_softening_m: float = number(0.0, 0.02)
    friction: float = number(0.01, 5.0)
    camera_distance_m: float = number(1e-3, 1.0)

    def __post_init__(self) -> None:
        if self.width_px % self.cell_px or self.height_px % self.cell_px:
            raise ValueError(
                f"key 'cell_px': expected a divisor of width_px and height_px "
                f"({self.width_px}, {self.height_px}), got {self.cell_px}"
            )

    @property
    def cell_m(self) -> float:
        """Side of a physics cell, m."""
        return self.cell_px * self.mm_per_px * 1e-3


def gel_profile(name_or_path: str) -> GelProfile:
    """The simulated gel of sensor ``NAME`` (``configs/sensors/NAME_gel.yaml``) or of a gel
    YAML path: the file's mechanics, and the working image (``GEOMETRY_KEYS``) of the sensor
    profile its ``name`` key names. ConfigError naming the file if it repeats the geometry."""
    path = Path(name_or_path)
    if path.suffix not in (".yaml", ".yml"):
        path = CONFIG_ROOT / FOLDER / f"{name_or_path}{GEL_SUFFIX}.yaml"
        if not path.exists():
            gels = [n for n in sensor_names() if (path.parent / f"{n}{GEL_SUFFIX}.yaml").exists()]
            raise ConfigError(
                f"unknown sensor configuration '{name_or_path}' (no gel profile {path.name}); "
                f"expected one of: {', '.join(gels)} (or a path to a gel .yaml file)"
            )
    data = load_yaml(path)
    for key in GEOMETRY_KEYS:
        if key in data:
            raise ConfigError(
                f"{path}: key '{key}' comes from the sensor profile "
                f"(configs/sensors/NAME.yaml, NAME the key 'name'); remove it here"
            )
    if "name" not in data:
        raise ConfigError(f"{path}: missing key 'name'")
    if data["name"] not in sensor_names():
        raise ConfigError(
            f"{path}: key 'name': expected the name of a sensor profile "
            f"({', '.join(sensor_names())}), got {show(data['name'])}"
        )
    sensor = sensor_profile(data["name"])
    geometry = {key: getattr(sensor, key) for key in GEOMETRY_KEYS}
    return build(GelProfile, {**data, **geometry}, source=str(path))


@config_dataclass
class ObjectShape(Config):
    """The grasped object's face against the gel.

    ``kind``: ``plate`` (a flat face larger than the gel), ``square_peg`` (a flat face
    ``width_m`` wide, its axis crossing the whole gel) or ``round_peg`` (a cylinder of
    diameter ``width_m`` lying on the gel). ``axis``: the S axis the peg's axis runs along.
    """

    kind: ObjectKind
    width_m: float = number(1e-3, 0.2)
    axis: Literal["x", "y"]


PLATE = ObjectShape("plate", 0.05, "y")
SQUARE_PEG = ObjectShape("square_peg", 0.010, "y")
ROUND_PEG = ObjectShape("round_peg", 0.010, "y")
SHAPES = {"plate": PLATE, "square_peg": SQUARE_PEG, "round_peg": ROUND_PEG}
