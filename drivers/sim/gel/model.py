"""The gel model: grip force and wrench in, contact state and camera image field out.

``GelModel(profile, shape).solve(grip_force_n, wrench)`` places the object, solves the
normal contact (pressure, lift-off), then the tangential one (stick, partial and gross
slip, in-plane rotation), convolves the tractions with the layer's Green's functions and
projects the surface displacement through the camera. Every unit is SI except the image
field, which is in px of the camera's working image (the renderer's input).

The model has no memory: it is quasi-static and each call is independent. A scene that
needs history (an object that slid keeps its new place) moves the object with
``offset_m``/``angle_rad``; ``start`` only seeds the solvers for speed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np

from drivers.sim.gel.contact import (
    NormalContact,
    TangentialContact,
    solve_normal,
    solve_tangential,
)
from drivers.sim.gel.footprint import Footprint, PhysicsGrid, place_object
from drivers.sim.gel.layer import ElasticLayer
from drivers.sim.gel.profile import GelProfile, ObjectShape


@dataclass(frozen=True)
class Wrench:
    """A wrench in frame S about its origin: forces N, torques N*m. In the model, the wrench
    the gel exerts on the object (fz on top of the grip force)."""

    fx: float = 0.0
    fy: float = 0.0
    fz: float = 0.0
    tau_x: float = 0.0
    tau_y: float = 0.0
    tau_z: float = 0.0

    def as_array(self) -> np.ndarray:
        return np.array([self.fx, self.fy, self.fz, self.tau_x, self.tau_y, self.tau_z])


@dataclass(frozen=True)
class GelState:
    """One solved contact. ``field_px``: forward image displacement of the view's cells,
    px (view rows, view cols, 2), relative to the undeformed gel; ``surface_m``: gel
    surface displacement on the whole grid (rows, cols, 3: x, y, toward the camera), m;
    ``carried``: the wrench the contact actually exerts (equals the request unless the
    object tipped over or slid); ``slip_fraction``: share of the loaded cells at the
    friction limit."""

    normal: NormalContact
    tangential: TangentialContact
    footprint: Footprint
    surface_m: np.ndarray
    field_px: np.ndarray
    carried: Wrench

    @property
    def in_contact(self) -> np.ndarray:
        return self.normal.force_n > 0

    @property
    def slip_fraction(self) -> float:
        loaded = self.in_contact
        if not loaded.any():
            return 0.0
        return float(self.tangential.slipping[loaded].mean())

    @property
    def lifted_off(self) -> bool:
        """Part of a flat face has separated from a flat gel where it could touch (cells of
        zero sag without force); a curved face or a dome changes its patch instead."""
        return bool(np.any(self.footprint.mask & (self.footprint.sag_m == 0) & ~self.in_contact))


class GelModel:
    """The gel of ``profile`` holding an object of ``shape`` (see the module docstring)."""

    def __init__(self, profile: GelProfile, shape: ObjectShape) -> None:
        self.profile, self.shape = profile, shape
        self.grid = PhysicsGrid.for_profile(profile)
        self.layer = ElasticLayer(profile, self.grid)
        area = self.grid.cell_m**2
        self._normal_k = area / self.layer.normal_compliance_m_pa
        self._shear_k = area / self.layer.shear_compliance_m_pa
        self._placed: dict[tuple[float, float, float], Footprint] = {}

    def footprint(self, offset_m: tuple[float, float] = (0.0, 0.0), angle_rad: float = 0.0):
        key = (float(offset_m[0]), float(offset_m[1]), float(angle_rad))
        if key not in self._placed:
            if len(self._placed) > 64:
                self._placed.clear()
            self._placed[key] = place_object(
                self.grid, self.profile, self.shape, offset_m, angle_rad
            )
        return self._placed[key]

    def solve(
        self,
        grip_force_n: float,
        wrench: Wrench,
        offset_m: tuple[float, float] = (0.0, 0.0),
        angle_rad: float = 0.0,
        start: GelState | None = None,
    ) -> GelState:
        """The contact under ``grip_force_n`` (N, >= 0) and ``wrench``; the object's face
        centred at ``offset_m`` and turned by ``angle_rad``; ``start``: a nearby solution to
        start the solvers from (a tipped or grossly slipping one seeds nothing: it has no
        rigid-body pose to start from)."""
        _check_inputs(grip_force_n, wrench, offset_m, angle_rad)
        foot = self.footprint(offset_m, angle_rad)
        x, y = self.grid.x_m, self.grid.y_m
        normal = solve_normal(
            x,
            y,
            foot.sag_m,
            self._normal_k * foot.edge_weight,
            (grip_force_n + wrench.fz, wrench.tau_x, wrench.tau_y),
            None if start is None or not start.normal.balanced else start.normal.rigid,
        )
        tangential = solve_tangential(
            x,
            y,
            np.where(normal.force_n > 0, self._shear_k, 0.0),
            self.profile.friction * normal.force_n,
            (wrench.fx, wrench.fy, wrench.tau_z),
            None if start is None or start.tangential.gross_slip else start.tangential.rigid,
        )
        # The gel takes the opposite of what it exerts on the object.
        surface = self.layer.surface_displacement_m(normal.force_n, -tangential.force_n)
        f, q = normal.force_n, tangential.force_n
        carried = Wrench(
            fx=float(q[..., 0].sum()),
            fy=float(q[..., 1].sum()),
            fz=float(f.sum()) - grip_force_n,
            tau_x=float((f * y).sum()),
            tau_y=float(-(f * x).sum()),
            tau_z=float((x * q[..., 1] - y * q[..., 0]).sum()),
        )
        return GelState(
            normal, tangential, foot, surface, self.layer.image_field_px(surface), carried
        )


def _check_inputs(
    grip_force_n: float, wrench: Wrench, offset_m: tuple[float, float], angle_rad: float
) -> None:
    """Raise ValueError naming the first input that is not a finite number (or a negative
    grip force); a NaN placement would otherwise pass silently as 'no contact'."""
    if not (math.isfinite(grip_force_n) and grip_force_n >= 0):
        raise ValueError(
            f"gel model: grip_force_n: expected a finite force >= 0 N, got {grip_force_n!r}"
        )
    named = [(f"wrench.{f.name}", getattr(wrench, f.name)) for f in fields(Wrench)]
    named += [("offset_m[0]", offset_m[0]), ("offset_m[1]", offset_m[1])]
    for name, value in [*named, ("angle_rad", angle_rad)]:
        if not math.isfinite(value):
            raise ValueError(f"gel model: {name}: expected a finite number, got {value!r}")
