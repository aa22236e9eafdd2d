"""The pipeline's output: one wrench estimate per tactile frame."""

from __future__ import annotations

from dataclasses import dataclass

# The estimate's values (every field but the timestamp and the flags), in a fixed order.
VALUE_FIELDS = (
    "tau_x",
    "tau_y",
    "tau_z",
    "shear_x",
    "shear_y",
    "normal",
    "fv_tau_x",
    "fv_tau_y",
    "fv_tau_z",
)
# The estimate's flags, in a fixed order.
FLAG_FIELDS = (
    "contact",
    "degenerate",
    "slip_suspected",
    "slip_gross",
    "rezero_recommended",
    "zeroing",
    "calibrated",
)


@dataclass(frozen=True, slots=True)
class WrenchEstimate:
    """Torques and forces the gel exerts on the grasped object, in sensor frame S.

    Without a calibration (``calibrated`` False) the values are raw: tau_x, tau_y and the
    shear in mm, tau_z in mm^2, normal in mm. With one, torques are N*m and forces N.

    * ``tau_x``, ``tau_y``: tilt torques (tactile dipole moment);
    * ``tau_z``: in-plane torque (NHHD rotational part);
    * ``shear_x``, ``shear_y``: shear (NHHD harmonic part);
    * ``normal``: normal-force index (NHHD diverging part), relative to the zeroed grasp;
    * ``fv_tau_x``, ``fv_tau_y``, ``fv_tau_z``: the FingerVision baseline's torques;
    * ``t_s``: the frame's timestamp, s.

    Flags: ``contact`` -- the field's mean magnitude exceeds the contact threshold;
    ``degenerate`` -- the divergence on the dipole's grid is zero everywhere, so the tilt
    torque is zero for want of information, not measured (with one sign of divergence
    absent the tilt is still estimated, controller/tactile/dipole.py); ``slip_suspected``
    -- the slip detector sees part of the contact slipping (incipient or gross slip);
    ``slip_gross`` -- it sees the object sliding as a whole; ``rezero_recommended`` --
    after gross slip the load was released and the field settled, so the zeroing reference
    should be refreshed (controller/tactile/slip.py; all three stay False when the detector
    is disabled); ``zeroing`` -- the reference is still being captured, all values are zero.
    """

    t_s: float
    tau_x: float
    tau_y: float
    tau_z: float
    shear_x: float
    shear_y: float
    normal: float
    fv_tau_x: float
    fv_tau_y: float
    fv_tau_z: float
    contact: bool
    degenerate: bool
    slip_suspected: bool
    slip_gross: bool
    rezero_recommended: bool
    zeroing: bool
    calibrated: bool

    @classmethod
    def zero(cls, t_s: float, *, zeroing: bool, calibrated: bool) -> WrenchEstimate:
        """An all-zero estimate (used while the reference is captured)."""
        return cls(
            t_s,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
            contact=False,
            degenerate=True,
            slip_suspected=False,
            slip_gross=False,
            rezero_recommended=False,
            zeroing=zeroing,
            calibrated=calibrated,
        )
