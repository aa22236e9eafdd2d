"""Meanings of the xArm SDK's codes, for error messages.

Four code spaces, never to be mixed up:

* **API codes**: the ``code`` every ``XArmAPI`` call returns (0 = success). Table below,
  from the SDK's documentation ``doc/api/xarm_api_code.md`` ("API Code") and its
  ``xarm/x3/code.py`` (``APIState``), xarm-python-sdk 1.18.
* **Controller error codes** (``XArmAPI.error_code``) and **controller warning codes**
  (``XArmAPI.warn_code``): looked up in the SDK's own tables
  (``xarm/core/config/x_code.py``: ``ControllerError``, ``ControllerWarn``), which give a
  title and what to do.
* **Mode and state codes**: what ``set_mode``/``set_state`` take and ``XArmAPI.mode``/
  ``XArmAPI.state`` report (the SDK's docstrings of those properties). The driver maps them
  to ``core.devices.ArmMode``/``ArmState`` here; no raw mode or state code leaves
  ``drivers.arm``. Note that the *command* ``set_state(0)`` ("ready to move") is answered
  by the *reported* state 2 ("sleeping": armed, at rest).
"""

from __future__ import annotations

from core.devices import ArmMode, ArmState
from drivers.arm.xarm_sdk import import_sdk

API_CODE_MEANINGS: dict[int, str] = {
    -12: "running a Blockly app failed",
    -11: "converting a Blockly app failed",
    -9: "emergency stop",
    -8: "out of range",
    -7: "joint angle limit",
    -6: "Cartesian position limit",
    -4: "command does not exist",
    -3: "API exception, possibly a parameter error",
    -2: "xArm is not ready: motion not enabled or state not set",
    -1: "xArm is disconnected or not connected",
    0: "success",
    1: "the controller has an error that has not been cleared",
    2: "the controller has a warning that has not been cleared",
    3: "timed out waiting for the controller's reply",
    4: "TCP reply length error",
    5: "TCP reply number error",
    6: "TCP protocol flag error",
    7: "TCP reply does not match the command sent",
    8: "sending the command failed, possibly a network fault",
    9: "state is not ready to move",
    10: "the result is invalid",
    11: "other error",
    12: "parameter error",
    51: "the mode is not correct",
    100: "timed out waiting for the motion to finish",
    101: "too many consecutive failed state checks while waiting",
}

MODE_CODES: dict[ArmMode, int] = {ArmMode.POSITION: 0, ArmMode.SERVO: 1, ArmMode.VELOCITY: 5}
"""The ``set_mode`` code of each mode the driver commands."""

_MODE_OF_CODE = {
    0: ArmMode.POSITION,
    1: ArmMode.SERVO,
    2: ArmMode.MANUAL,  # joint teaching
    3: ArmMode.MANUAL,  # Cartesian teaching
    5: ArmMode.VELOCITY,  # Cartesian velocity (4 is joint velocity: OTHER)
}
_STATE_OF_CODE = {1: ArmState.MOVING, 2: ArmState.READY, 3: ArmState.PAUSED, 4: ArmState.STOPPED}

SET_STATE_READY = 0  # set_state(0): enable motion in the mode set last
SET_STATE_STOP = 4  # set_state(4): stop and drop queued motion; the controller reports state 4
STATE_STOPPED = 4  # the reported state after set_state(4)

NOT_CONNECTED = -1
HAS_ERROR = 1
HAS_WARNING = 2
REPLY_TIMEOUT = 3
WAIT_FINISH_TIMEOUT = 100


def mode_from_code(code: int) -> ArmMode:
    """The ``ArmMode`` of a mode code reported by ``XArmAPI.mode``."""
    return _MODE_OF_CODE.get(code, ArmMode.OTHER)


def state_from_code(code: int) -> ArmState:
    """The ``ArmState`` of a state code reported by ``XArmAPI.state``."""
    return _STATE_OF_CODE.get(code, ArmState.UNKNOWN)


def describe_api_code(code: int) -> str:
    """``"API code N: meaning"`` for a code returned by an XArmAPI call."""
    return f"API code {code}: {API_CODE_MEANINGS.get(code, 'undocumented code')}"


def describe_controller_error(code: int) -> str:
    """``"controller error C<code>: title. what to do"`` from the SDK's error table."""
    import_sdk()
    from xarm.core.config.x_code import ControllerError

    return _describe("controller error C", ControllerError(code))


def describe_controller_warning(code: int) -> str:
    """``"controller warning W<code>: title. what to do"`` from the SDK's warning table."""
    import_sdk()
    from xarm.core.config.x_code import ControllerWarn

    return _describe("controller warning W", ControllerWarn(code))


def _describe(prefix: str, entry: object) -> str:
    title = entry.title["en"]  # type: ignore[attr-defined]
    advice = entry.description["en"]  # type: ignore[attr-defined]
    text = f"{prefix}{entry.code}: {title}"  # type: ignore[attr-defined]
    return f"{text}. {advice}" if advice else text
