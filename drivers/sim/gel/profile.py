"""Gel profiles and grasped-object shapes of the gel simulator (SI units: m, Pa, N).

A ``GelProfile`` is the simulated half of a sensor profile: the camera's working image (the
same size and scale as ``configs/sensors/NAME.yaml``) plus the gel's mechanics. Profiles live
in ``configs/sensors/NAME_gel.yaml``; docs/SIMULATION.md explains each parameter, its
default and its source. The elastic gains are parameters on purpose: the simulator is meant
to be right about trends (where lift-off and slip begin, how the field changes shape), not
about absolute gains, which every real sensor needs a calibration for.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from drivers.validation import check_choice, check_int, check_range

ObjectKind = Literal["plate", "square_peg", "round_peg"]
OBJECT_KINDS = ("plate", "square_peg", "round_peg")


@dataclass(frozen=True)
class GelProfile:
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
    width_px: int
    height_px: int
    mm_per_px: float
    cell_px: int
    gel_width_m: float
    gel_height_m: float
    thickness_m: float
    young_modulus_pa: float
    poisson_ratio: float
    dome_radius_m: float | None
    edge_softening_m: float
    friction: float
    camera_distance_m: float

    def __post_init__(self) -> None:
        check_int("width_px", self.width_px, 16, 4096)
        check_int("height_px", self.height_px, 16, 4096)
        check_range("mm_per_px", self.mm_per_px, 1e-3, 1.0)
        check_int("cell_px", self.cell_px, 1, 64)
        if self.width_px % self.cell_px or self.height_px % self.cell_px:
            raise ValueError(
                f"key 'cell_px': expected a divisor of width_px and height_px "
                f"({self.width_px}, {self.height_px}), got {self.cell_px}"
            )
        check_range("gel_width_m", self.gel_width_m, 1e-3, 0.2)
        check_range("gel_height_m", self.gel_height_m, 1e-3, 0.2)
        check_range("thickness_m", self.thickness_m, 1e-4, 0.02)
        check_range("young_modulus_pa", self.young_modulus_pa, 1e3, 1e8)
        check_range("poisson_ratio", self.poisson_ratio, 0.0, 0.499)
        if self.dome_radius_m is not None:
            check_range("dome_radius_m", self.dome_radius_m, 1e-3, 10.0)
        check_range("edge_softening_m", self.edge_softening_m, 0.0, 0.02)
        check_range("friction", self.friction, 0.01, 5.0)
        check_range("camera_distance_m", self.camera_distance_m, 1e-3, 1.0)

    @property
    def cell_m(self) -> float:
        """Side of a physics cell, m."""
        return self.cell_px * self.mm_per_px * 1e-3


@dataclass(frozen=True)
class ObjectShape:
    """The grasped object's face against the gel.

    ``kind``: ``plate`` (a flat face larger than the gel), ``square_peg`` (a flat face
    ``width_m`` wide, its axis crossing the whole gel) or ``round_peg`` (a cylinder of
    diameter ``width_m`` lying on the gel). ``axis``: the S axis the peg's axis runs along.
    """

    kind: ObjectKind
    width_m: float
    axis: Literal["x", "y"]

    def __post_init__(self) -> None:
        check_choice("kind", self.kind, OBJECT_KINDS)
        check_range("width_m", self.width_m, 1e-3, 0.2)
        check_choice("axis", self.axis, ("x", "y"))


PLATE = ObjectShape("plate", 0.05, "y")
SQUARE_PEG = ObjectShape("square_peg", 0.010, "y")
ROUND_PEG = ObjectShape("round_peg", 0.010, "y")
SHAPES = {"plate": PLATE, "square_peg": SQUARE_PEG, "round_peg": ROUND_PEG}
