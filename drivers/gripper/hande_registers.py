"""Robotiq Hand-E register map: command encoding, status decoding, fault table, unit mapping.

Source: Robotiq Hand-E instruction manual, section 4 "Control" (register mapping, robot output
registers, robot input registers, Modbus RTU examples). Each Modbus register holds two bytes,
big-endian: the lower-numbered byte is the register's high byte. The manual's own example
``09 10 03 E8 00 03 06 09 00 00 FF FF FF`` writes ``[0x0900, 0x00FF, 0xFFFF]`` (rACT=1,
rGTO=1, rPR=0xFF, rSP=0xFF, rFR=0xFF) and its status reply ``B9 00 00 FF BD 00`` reads as
gACT=1, gGTO=1, gSTA=3, gOBJ=2, gPR=0xFF, gPO=0xBD.

Command (robot output) registers, from ``COMMAND_ADDRESS`` (0x03E8):

=======  =======================================  ==============================
address  high byte                                low byte
=======  =======================================  ==============================
0x03E8   ACTION REQUEST: rARD b5, rATR b4,        reserved
         rGTO b3, rACT b0
0x03E9   reserved                                 POSITION REQUEST rPR (0 = open)
0x03EA   SPEED rSP (0 = slowest)                  FORCE rFR (0 = weakest)
=======  =======================================  ==============================

Status (robot input) registers, from ``STATUS_ADDRESS`` (0x07D0):

=======  =======================================  ==============================
address  high byte                                low byte
=======  =======================================  ==============================
0x07D0   GRIPPER STATUS: gOBJ b7-6, gSTA b5-4,    reserved
         gGTO b3, gACT b0
0x07D1   FAULT STATUS: kFLT b7-4, gFLT b3-0       POSITION REQUEST ECHO gPR
0x07D2   POSITION gPO (0 = open)                  CURRENT gCU (about 10 mA/count)
=======  =======================================  ==============================
"""

from __future__ import annotations

from dataclasses import dataclass

COMMAND_ADDRESS = 0x03E8
STATUS_ADDRESS = 0x07D0
REGISTER_COUNT = 3  # both blocks hold 6 bytes

ACT_BIT = 0x01  # rACT: activate (clearing it resets the gripper and clears faults)
GTO_BIT = 0x08  # rGTO: go to the requested position (rATR/rARD, auto-release, are not used)

GSTA_ACTIVATING = 1  # gSTA: activation in progress
GSTA_ACTIVATED = 3  # gSTA: activation completed

# Hand-E specification: finger speed 20-150 mm/s and grip force 20-185 N, mapped by the
# gripper linearly (as assumed here; the manual only states 0x00 = minimum, 0xFF = maximum).
SPEED_RANGE_M_S = (0.020, 0.150)
FORCE_RANGE_N = (20.0, 185.0)

# gFLT meanings from the manual's FAULT STATUS table. 0x05 and 0x07 are priority faults,
# 0x08 and 0x09 minor faults (solid red LED), 0x0A-0x0F major faults that need a reset:
# clear then set rACT (which re-runs the activation and moves the fingers).
FAULT_MESSAGES: dict[int, str] = {
    0x05: "action delayed: the (re-)activation must complete before the action is performed",
    0x06: "fault 0x06 is not documented in the Robotiq Hand-E manual",
    0x07: "the activation bit (rACT) must be set before the action is performed",
    0x08: "maximum operating temperature exceeded: wait for the gripper to cool down",
    0x09: "no communication during at least 1 second",
    0x0A: "under minimum operating voltage: check the 24 V supply",
    0x0B: "automatic release in progress",
    0x0C: "internal fault: contact Robotiq support",
    0x0D: "activation fault: verify that nothing interferes with the fingers",
    0x0E: "overcurrent triggered",
    0x0F: "automatic release completed",
}
MAJOR_FAULT_MIN = 0x0A


@dataclass(frozen=True)
class RawStatus:
    """The status registers decoded field by field; names are the manual's."""

    gACT: int  # 1 = activated (echo of rACT)
    gGTO: int  # 1 = going to the requested position (echo of rGTO)
    gSTA: int  # 0 reset, 1 activating, 3 activated
    gOBJ: int  # object detection, see core.devices.GripperObject; ignore when gGTO == 0
    gFLT: int  # gripper fault code, 0 = none
    kFLT: int  # controller fault nibble, 0 = none
    gPR: int  # echo of the requested position, counts
    gPO: int  # finger position, counts (0 = open)
    gCU: int  # motor current, about 10 mA per count


def encode_command(*, act: bool, go: bool, position: int, speed: int, force: int) -> list[int]:
    """Command registers (from ``COMMAND_ADDRESS``) for the given bits and 0-255 counts."""
    for name, value in (("position", position), ("speed", speed), ("force", force)):
        if not 0 <= value <= 0xFF:
            raise ValueError(f"{name} count must be in [0, 255], got {value}")
    action = (ACT_BIT if act else 0) | (GTO_BIT if go else 0)
    return [action << 8, position, (speed << 8) | force]


def decode_status(registers: list[int]) -> RawStatus:
    """Decode the three status registers read from ``STATUS_ADDRESS``."""
    if len(registers) != REGISTER_COUNT:
        raise ValueError(f"expected {REGISTER_COUNT} status registers, got {len(registers)}")
    status, fault_and_echo, position_and_current = registers
    status_byte = status >> 8
    fault_byte = fault_and_echo >> 8
    return RawStatus(
        gACT=status_byte & 0x01,
        gGTO=(status_byte >> 3) & 0x01,
        gSTA=(status_byte >> 4) & 0x03,
        gOBJ=(status_byte >> 6) & 0x03,
        gFLT=fault_byte & 0x0F,
        kFLT=fault_byte >> 4,
        gPR=fault_and_echo & 0xFF,
        gPO=position_and_current >> 8,
        gCU=position_and_current & 0xFF,
    )


def fault_message(gflt: int, kflt: int = 0) -> str:
    """Human-readable meaning of the fault nibbles ("" when there is no fault)."""
    parts = []
    if gflt:
        text = FAULT_MESSAGES.get(gflt, "not documented in the Robotiq Hand-E manual")
        if gflt >= MAJOR_FAULT_MIN:
            text += " (major fault: reset and re-activate the gripper)"
        parts.append(f"gFLT 0x{gflt:02X}: {text}")
    if kflt:
        parts.append(f"kFLT 0x{kflt:X}: controller fault, see the Robotiq manual")
    return "; ".join(parts)


def _count_in(value: float, low: float, high: float) -> int:
    return round((value - low) / (high - low) * 0xFF)


def speed_count(speed_m_s: float) -> int:
    """rSP count for a finger speed in m/s (must lie in ``SPEED_RANGE_M_S``)."""
    low, high = SPEED_RANGE_M_S
    if not low <= speed_m_s <= high:
        raise ValueError(f"speed_m_s: expected a number in [{low}, {high}], got {speed_m_s!r}")
    return _count_in(speed_m_s, low, high)


def force_count(force_n: float) -> int:
    """rFR count for a grip force in N (must lie in ``FORCE_RANGE_N``)."""
    low, high = FORCE_RANGE_N
    if not low <= force_n <= high:
        raise ValueError(f"force_n: expected a number in [{low}, {high}], got {force_n!r}")
    return _count_in(force_n, low, high)


def position_count(width_m: float, open_count: int, closed_count: int, stroke_m: float) -> int:
    """rPR count for a finger opening in metres, from the calibrated open/closed counts."""
    if not 0.0 <= width_m <= stroke_m:
        raise ValueError(f"width_m: expected a number in [0, {stroke_m}], got {width_m!r}")
    return round(closed_count - width_m / stroke_m * (closed_count - open_count))


def width_from_count(count: int, open_count: int, closed_count: int, stroke_m: float) -> float:
    """Finger opening in metres for a gPO count, clamped to [0, stroke_m]."""
    width = (closed_count - count) / (closed_count - open_count) * stroke_m
    return min(max(width, 0.0), stroke_m)
