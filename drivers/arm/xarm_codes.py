"""Meanings of the xArm SDK's codes, for error messages.

Three code spaces, never to be mixed up:

* **API codes**: the ``code`` every ``XArmAPI`` call returns (0 = success). Table below,
  from the SDK's documentation ``doc/api/xarm_api_code.md`` ("API Code") and its
  ``xarm/x3/code.py`` (``APIState``), xarm-python-sdk 1.18.
* **Controller error codes** (``XArmAPI.error_code``) and **controller warning codes**
  (``XArmAPI.warn_code``): looked up in the SDK's own tables
  (``xarm/core/config/x_code.py``: ``ControllerError``, ``ControllerWarn``), which give a
  title and what to do.
"""

from __future__ import annotations

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

NOT_CONNECTED = -1
HAS_ERROR = 1
HAS_WARNING = 2
REPLY_TIMEOUT = 3
WAIT_FINISH_TIMEOUT = 100


def describe_api_code(code: int) -> str:
    """``"API code N: meaning"`` for a code returned by an XArmAPI call."""
    return f"API code {code}: {API_CODE_MEANINGS.get(code, 'undocumented code')}"


def describe_controller_error(code: int) -> str:
    """``"controller error C<code>: title. what to do"`` from the SDK's error table."""
    from xarm.core.config.x_code import ControllerError

    return _describe("controller error C", ControllerError(code))


def describe_controller_warning(code: int) -> str:
    """``"controller warning W<code>: title. what to do"`` from the SDK's warning table."""
    from xarm.core.config.x_code import ControllerWarn

    return _describe("controller warning W", ControllerWarn(code))


def _describe(prefix: str, entry: object) -> str:
    title = entry.title["en"]  # type: ignore[attr-defined]
    advice = entry.description["en"]  # type: ignore[attr-defined]
    text = f"{prefix}{entry.code}: {title}"  # type: ignore[attr-defined]
    return f"{text}. {advice}" if advice else text
