"""What touch has told the machine about the board during one run: the surface's height
(found on APPROACH's contact) and the plug's heights at INSERT's jams, from which the
plug's depth into the opening is judged (heights in m along B z).
"""

from __future__ import annotations

from scipy.spatial.transform import Rotation

from controller.insertion.motion import lowest_edge
from core.devices import Pose
from core.task_geometry import PlugGeometry


class TouchMemory:
    """The surface found by touch and the rim found by jams, for ``plug`` over an opening
    whose nominal height is ``nominal_z_m`` (used until the surface is touched)."""

    def __init__(self, plug: PlugGeometry, nominal_z_m: float) -> None:
        self.plug = plug
        self.nominal_z_m = nominal_z_m
        self.surface_z_m: float | None = None  # the board surface's height found by touch
        self._last_jam_z_m: float | None = None  # the lowest edge's height at the last jam
        self._rim_z_m: float | None = None  # ... at a jam no deeper than the one before it

    def edge_z(self, tcp: Pose, rotation: Rotation) -> float:
        """The height of the tip face's lowest edge (``motion.lowest_edge``)."""
        return float(lowest_edge(tcp, self.plug, rotation)[2])

    def touch_surface(self, tcp: Pose, rotation: Rotation) -> None:
        """The board's surface is where the lowest edge is now (contact on APPROACH)."""
        self.surface_z_m = self.edge_z(tcp, rotation)

    def new_catch(self) -> None:
        """SEARCH caught the opening again: no jam there yet."""
        self._last_jam_z_m = self._rim_z_m = None

    def depth(self, tcp: Pose, rotation: Rotation) -> float:
        """How far the tip face's lowest edge is below the board surface found by touch (the
        nominal opening's height before any touch), m."""
        surface = self.nominal_z_m if self.surface_z_m is None else self.surface_z_m
        return surface - self.edge_z(tcp, rotation)

    def depth_in(self, tcp: Pose, rotation: Rotation) -> float:
        """How far the plug is into the opening, m: ``depth``, or less, how far its lowest
        edge is below the rim it stood on at repeated jams (``note_jam``)."""
        depth = self.depth(tcp, rotation)
        if self._rim_z_m is None:
            return depth
        return min(depth, self._rim_z_m - self.edge_z(tcp, rotation))

    def entered(self, tcp: Pose, rotation: Rotation, enter_m: float) -> bool:
        """True when the plug is in the opening: ``depth_in`` at least ``enter_m``."""
        return self.depth_in(tcp, rotation) >= enter_m

    def note_jam(self, tcp: Pose, rotation: Rotation, enter_m: float) -> None:
        """A jam no deeper (by ``enter_m``) than the jam before it at this catch: the plug
        stands on the opening's rim, whatever the depth by touch says (that depth assumes
        the nominal grasp; an unknown in-grasp tilt moves the lowest edge by up to a
        millimetre). From then on the plug has entered only ``enter_m`` below where it
        stood, so ALIGN's width and yaw stages and INSERT's press run again."""
        edge_z = self.edge_z(tcp, rotation)
        last, self._last_jam_z_m = self._last_jam_z_m, edge_z
        if last is not None and edge_z > last - enter_m:
            self._rim_z_m = edge_z
