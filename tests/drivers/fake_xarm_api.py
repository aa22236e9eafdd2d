"""An in-memory fake of ``xarm.wrapper.XArmAPI`` (xarm-python-sdk 1.18.4) for driver tests.

It keeps the SDK's signatures and return conventions, as read in the SDK's source:

* Setters return an ``int`` code and getters a ``(code, value)`` tuple
  (``xarm/wrapper/xarm_api.py``, method docstrings).
* Not connected: setters return -1 and getters ``(-1, 'xArm is not connect')``, a string
  where a list is expected (``xarm/x3/decorator.py``: ``xarm_is_connected``,
  ``xarm_is_ready``). A forced -1 from a getter (``fail_next``) returns the same string.
* Motion commands (``set_position``, ``set_servo_cartesian``, ``vc_set_cartesian_velocity``,
  ``set_tcp_load``) pass the controller's reply through ``Base._check_code(code,
  is_move_cmd=True)`` (``xarm/x3/base.py``): 1 while an error is uncleared, 9 when the
  state is not ready (stopped, state 4), 0 with only a warning.
* ``motion_enable``, ``set_mode``, ``set_state`` use ``_check_code(code)``, which maps 1, 2
  and 9 to 0: they report success even while an error is present.
* ``set_tcp_offset`` (``xarm/x3/xarm.py``: ``XArm.set_tcp_offset``), ``clean_error`` and
  ``clean_warn`` (``Base.clean_error``/``clean_warn``) return the raw reply code; here 1
  when an error was present and 2 when a warning was (the reply's status flags).
* ``emergency_stop`` returns None (``XArm.emergency_stop``: ``set_state(4)`` until state 4).
* ``set_timeout(s)`` sets the reply timeout of later commands and returns it, connected or
  not (``Base.set_timeout``); ``connect`` resets it to 2 s (``Base._init``).
* ``connect`` raises a bare ``Exception('connect socket failed')`` when the socket fails,
  and calls the error/warning callbacks once with the current codes (``Base.connect``).
* The error/warning callback gets ``{'error_code': e, 'warn_code': w}``
  (``Base._report_error_warn_changed_callback``), only when the codes change
  (``only_report_err_warn_changed`` defaults to True). Here it runs synchronously; the SDK
  runs it on its report thread.
* ``get_position`` returns ``[x, y, z (mm), roll, pitch, yaw]`` rounded to 6 decimals,
  angles in radians when ``is_radian`` else degrees; ``get_servo_angle`` returns 7 angles
  (``Base.get_position``/``get_servo_angle``). ``is_radian=None`` means the constructor's
  ``is_radian``. Commands convert angles with ``to_radian(v, is_radian or i <= 2)``.
* ``vc_set_cartesian_velocity`` sends ``duration`` only with firmware >= 1.8.0, else -1
  (``XArm.vc_set_cartesian_velocity``).
* ``set_ft_sensor_enable(on_off)`` returns a code and ``get_ft_sensor_data(is_raw=False)``
  ``(code, [Fx, Fy, Fz (N), Tx, Ty, Tz (N*m)])``, the sensor's filtered, load-compensated
  wrench (``XArmAPI.get_ft_sensor_data``; ``XArm.get_ft_sensor_data`` returns the reply's
  six values after the code).
* ``state``: 1 moving, 2 sleeping (ready), 3 paused, 4 stopped; initially 4, mode 0
  (``Base._init``).

Controller model (simplified): ``motion_enable(True)`` enables the motors; ``set_mode(m)``
takes effect at the next ``set_state(0)``, which makes the state 2 (ready) when the motors
are enabled and no error is present; ``set_state(4)`` stops. A controller error
(``inject_error``) stops the arm (state 4); recovery needs ``clean_error``,
``motion_enable(True)`` and ``set_state(0)``. Accepted motion commands move the pose at
once (servo in mode 1, position in mode 0); velocity commands are only recorded.

Test hooks: ``calls`` (every call in order, with the controller's mode and state at that
moment and ``sent``, the command as the SDK would send it: mm and radians), ``pose``
(mm, rad), ``inject_error``, ``inject_warning``, ``fail_next``, ``refuse_connection``,
``sticky_error`` (clean_error cannot clear, like a pressed emergency stop button),
``ignore_stop`` (the controller does not reach state 4).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

NOT_CONNECTED = -1
NOT_CONNECTED_TEXT = "xArm is not connect"
HAS_ERROR = 1
HAS_WARNING = 2
STATE_NOT_READY = 9


@dataclass
class Call:
    """One API call: its name and arguments, the controller's active mode and state when it
    arrived, and what the SDK would have sent (mm and radians), if anything."""

    name: str
    args: tuple[Any, ...]
    kwargs: dict[str, Any]
    mode: int
    state: int
    sent: Any = field(default=None)


class FakeXArmAPI:
    """See the module docstring. Same constructor as ``XArmAPI``."""

    def __init__(self, port: str | None = None, is_radian: bool = False, do_not_open: bool = False):
        self.port = port
        self.calls: list[Call] = []
        self.pose = [300.0, 0.0, 200.0, math.pi, 0.0, 0.0]  # mm and rad, as the SDK holds it
        self.joints = [0.1, -0.2, 0.3, -0.4, 0.5, -0.6, 0.0]  # rad; the 7th is unused on xArm6
        self.version_number = (2, 3, 0)
        self.ft_wrench = [0.0] * 6  # the F/T sensor's reading: N, N*m in the flange's axes
        self.ft_enabled = False
        self.tcp_offset: list[float] | None = None  # mm and rad
        self.tcp_load: tuple[float, list[float]] | None = None  # kg, mm
        self.refuse_connection = False
        self.timeout_s = 2.0  # reply timeout of commands, s
        self.sticky_error = False
        self.ignore_stop = False
        self._default_is_radian = is_radian
        self._connected = False
        self._enabled = False
        self._mode = 0
        self._pending_mode = 0
        self._state = 4
        self._error_code = 0
        self._warn_code = 0
        self._callbacks: list[Callable[[dict[str, int]], None]] = []
        self._forced: dict[str, int] = {}
        if not do_not_open:
            self.connect()

    # ------------------------------------------------------------- test hooks

    def inject_error(self, code: int, notify: bool = True) -> None:
        """A controller error: the arm stops; the callbacks run unless ``notify`` is False
        (a report not yet received)."""
        self._error_code = code
        self._state = 4
        if notify:
            self._notify()

    def inject_warning(self, code: int) -> None:
        """A controller warning; the arm keeps its state."""
        self._warn_code = code
        self._notify()

    def fail_next(self, name: str, code: int) -> None:
        """Make the next call of method ``name`` (once connected) return ``code``."""
        self._forced[name] = code

    def drop_connection(self) -> None:
        """The link goes down without disconnect()."""
        self._connected = False

    def named(self, name: str) -> list[Call]:
        return [c for c in self.calls if c.name == name]

    # ------------------------------------------------------------- properties

    @property
    def connected(self) -> bool:
        return self._connected

    @property
    def default_is_radian(self) -> bool:
        return self._default_is_radian

    @property
    def mode(self) -> int:
        return self._mode

    @property
    def state(self) -> int:
        return self._state

    @property
    def error_code(self) -> int:
        return self._error_code

    @property
    def warn_code(self) -> int:
        return self._warn_code

    # ------------------------------------------------------------- lifecycle

    def connect(self, port=None, baudrate=None, timeout=None, axis=None, **kwargs) -> None:
        self._record("connect", (), dict(port=port, baudrate=baudrate, timeout=timeout, axis=axis))
        if self._connected:
            return
        if self.refuse_connection:
            raise Exception("connect socket failed")
        self.timeout_s = 2.0
        self._connected = True
        self._notify()

    def disconnect(self) -> None:
        self._record("disconnect", (), {})
        self._connected = False

    def set_timeout(self, timeout) -> float:
        self._record("set_timeout", (timeout,), {})
        self.timeout_s = timeout
        return timeout

    def register_error_warn_changed_callback(self, callback=None) -> bool:
        self._record("register_error_warn_changed_callback", (callback,), {})
        if not callable(callback):
            return False
        if callback not in self._callbacks:
            self._callbacks.append(callback)
        return True

    def release_error_warn_changed_callback(self, callback=None) -> bool:
        self._record("release_error_warn_changed_callback", (callback,), {})
        if callback is None:
            self._callbacks.clear()
            return True
        if callback in self._callbacks:
            self._callbacks.remove(callback)
            return True
        return False

    # ------------------------------------------------------------- setters

    def motion_enable(self, enable=True, servo_id=None) -> int:
        code = self._begin("motion_enable", (), dict(enable=enable, servo_id=servo_id))
        if code is None:
            self._enabled = bool(enable)
            code = 0
        return code

    def set_mode(self, mode=0, detection_param=0) -> int:
        code = self._begin("set_mode", (mode,), dict(detection_param=detection_param))
        if code is None:
            self._pending_mode = mode
            code = 0
        return code

    def set_state(self, state=0) -> int:
        code = self._begin("set_state", (state,), {})
        if code is None:
            if state == 0 and self._enabled and self._error_code == 0:
                self._mode = self._pending_mode
                self._state = 2
            elif state in (3, 4) and not (state == 4 and self.ignore_stop):
                self._state = state
            code = 0
        return code

    def clean_error(self) -> int:
        code = self._begin("clean_error", (), {})
        if code is None:
            code = HAS_ERROR if self._error_code else 0
            if self._error_code and not self.sticky_error:
                self._error_code = 0
                self._notify()
        return code

    def clean_warn(self) -> int:
        code = self._begin("clean_warn", (), {})
        if code is None:
            code = HAS_WARNING if self._warn_code else 0
            if self._warn_code:
                self._warn_code = 0
                self._notify()
        return code

    def emergency_stop(self) -> None:
        self._record("emergency_stop", (), {})
        if self._connected and not self.ignore_stop:
            self._state = 4

    def set_ft_sensor_enable(self, on_off) -> int:
        code = self._begin("set_ft_sensor_enable", (on_off,), {})
        if code is None:
            self.ft_enabled = bool(on_off)
        return 0 if code is None else code

    def set_tcp_offset(self, offset, is_radian=None, wait=True, **kwargs) -> int:
        sent = self._angles_to_radian(offset, is_radian)
        code = self._begin("set_tcp_offset", (offset,), dict(is_radian=is_radian, wait=wait), sent)
        if code is None:
            self.tcp_offset = sent
            code = HAS_ERROR if self._error_code else HAS_WARNING if self._warn_code else 0
        return code

    def set_tcp_load(self, weight, center_of_gravity, wait=False, **kwargs) -> int:
        sent = (float(weight), [float(v) for v in center_of_gravity])
        code = self._begin("set_tcp_load", (weight, center_of_gravity), dict(wait=wait), sent)
        if code is None:
            code = self._motion_code()
            if code == 0:
                self.tcp_load = sent
        return code

    def set_servo_cartesian(
        self,
        mvpose,
        speed=None,
        mvacc=None,
        mvtime=0,
        is_radian=None,
        is_tool_coord=False,
        **kwargs,
    ) -> int:
        sent = self._angles_to_radian(mvpose, is_radian)
        kw = dict(
            speed=speed,
            mvacc=mvacc,
            mvtime=mvtime,
            is_radian=is_radian,
            is_tool_coord=is_tool_coord,
        )
        code = self._begin("set_servo_cartesian", (mvpose,), kw, sent)
        if code is None:
            code = self._motion_code()
            if code == 0 and self._mode == 1 and not is_tool_coord:
                self.pose = sent
        return code

    def vc_set_cartesian_velocity(
        self, speeds, is_radian=None, is_tool_coord=False, duration=-1, **kwargs
    ) -> int:
        speeds_sent = self._angles_to_radian(list(speeds) + [0.0] * (6 - len(speeds)), is_radian)
        duration_sent = duration if tuple(self.version_number) >= (1, 8, 0) else -1
        kw = dict(is_radian=is_radian, is_tool_coord=is_tool_coord, duration=duration)
        code = self._begin("vc_set_cartesian_velocity", (speeds,), kw, (speeds_sent, duration_sent))
        return self._motion_code() if code is None else code

    def set_position(
        self, x=None, y=None, z=None, roll=None, pitch=None, yaw=None, radius=None,
        speed=None, mvacc=None, mvtime=None, relative=False, is_radian=None,
        wait=False, timeout=None, **kwargs,
    ) -> int:  # fmt: skip
        given = [x, y, z, roll, pitch, yaw]
        is_rad = self._default_is_radian if is_radian is None else is_radian
        target = [
            self.pose[i] if v is None else float(v) if i <= 2 or is_rad else math.radians(v)
            for i, v in enumerate(given)
        ]
        kw = dict(
            x=x, y=y, z=z, roll=roll, pitch=pitch, yaw=yaw, radius=radius, speed=speed,
            mvacc=mvacc, mvtime=mvtime, relative=relative, is_radian=is_radian, wait=wait,
            timeout=timeout,
        )  # fmt: skip
        code = self._begin("set_position", (), kw, {"pose": target, "speed": speed})
        if code is None:
            code = self._motion_code()
            if code == 0 and self._mode == 0 and not relative:
                self.pose = target
        return code

    # ------------------------------------------------------------- getters

    def get_position(self, is_radian=None) -> tuple[int, Any]:
        code = self._begin("get_position", (), dict(is_radian=is_radian))
        is_rad = self._default_is_radian if is_radian is None else is_radian
        values = [v if i <= 2 or is_rad else math.degrees(v) for i, v in enumerate(self.pose)]
        return self._reply(code, [float(f"{v:.6f}") for v in values])

    def get_servo_angle(self, servo_id=None, is_radian=None, is_real=False) -> tuple[int, Any]:
        code = self._begin(
            "get_servo_angle", (), dict(servo_id=servo_id, is_radian=is_radian, is_real=is_real)
        )
        is_rad = self._default_is_radian if is_radian is None else is_radian
        return self._reply(
            code, [float(f"{q if is_rad else math.degrees(q):.6f}") for q in self.joints]
        )

    def get_ft_sensor_data(self, is_raw=False) -> tuple[int, Any]:
        code = self._begin("get_ft_sensor_data", (), dict(is_raw=is_raw))
        return self._reply(code, [float(v) for v in self.ft_wrench])

    def get_err_warn_code(self, show=False, lang="en") -> tuple[int, Any]:
        code = self._begin("get_err_warn_code", (), dict(show=show, lang=lang))
        return self._reply(code, [self._error_code, self._warn_code])

    # ------------------------------------------------------------- internals

    def _record(self, name: str, args: tuple, kwargs: dict, sent: Any = None) -> None:
        self.calls.append(Call(name, args, kwargs, self._mode, self._state, sent))

    def _begin(self, name: str, args: tuple, kwargs: dict, sent: Any = None) -> int | None:
        """Record the call; return its code if decided already (not connected, forced)."""
        self._record(name, args, kwargs, sent)
        if not self._connected:
            return NOT_CONNECTED
        return self._forced.pop(name, None)

    def _reply(self, code: int | None, value: list[Any]) -> tuple[int, Any]:
        if code == NOT_CONNECTED:
            return NOT_CONNECTED, NOT_CONNECTED_TEXT
        return (0 if code is None else code), value

    def _motion_code(self) -> int:
        if self._error_code:
            return HAS_ERROR
        if self._state >= 4:
            return STATE_NOT_READY
        return 0

    def _angles_to_radian(self, values, is_radian: bool | None) -> list[float]:
        is_rad = self._default_is_radian if is_radian is None else is_radian
        return [float(v) if i <= 2 or is_rad else math.radians(v) for i, v in enumerate(values[:6])]

    def _notify(self) -> None:
        item = {"error_code": self._error_code, "warn_code": self._warn_code}
        for callback in list(self._callbacks):
            callback(item)
