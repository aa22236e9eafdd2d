"""Gamepad driver on SDL's game-controller API (``pygame._sdl2.controller``).

SDL's game-controller layer gives the same axis and button names for Xbox, PS4 and PS5 pads
(see ``drivers.gamepad.mapping``); ``PygameGamepad.read()`` returns them by action name.

SDL set-up (``init_sdl``):
- the hint ``SDL_JOYSTICK_ALLOW_BACKGROUND_EVENTS=1`` is set (unless already set in the
  environment) before SDL's joystick subsystem starts, so the pad keeps working when the
  process has a window without focus. It must precede any other pygame joystick start-up to
  take effect (SDL reads it when the subsystem initialises).
- pygame pumps events only with its video subsystem up. If ``pygame.display`` is not yet
  initialised, the driver starts it with ``SDL_VIDEODRIVER`` from the environment or else
  ``dummy`` (no display needed; the variable is restored afterwards). An application that
  wants a real pygame window initialises ``pygame.display`` before ``connect()``.
- the driver owns pygame's event queue: every ``read()`` handles the controller hot-plug
  events and discards all other events.

Hot-plug: ``read()`` pumps the events. When the open pad is removed it is closed, and
``read()`` returns ``connected=False`` with every axis 0.0 and every button released, without
raising. At the next controller-added event the driver opens the *first* game controller SDL
lists (lowest device index), the same rule ``connect()`` uses. ``is_connected`` tells whether
the driver is open (between ``connect()`` and ``disconnect()``); ``GamepadState.connected``
whether a pad is attached right now.
"""

from __future__ import annotations

import os
from typing import Self

os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")  # no banner on stdout at import

import pygame  # noqa: E402
from pygame._sdl2 import controller as sdl_controller  # noqa: E402

from core.clock import Clock, MonotonicClock  # noqa: E402
from core.devices import ContextManagedDevice, GamepadState  # noqa: E402
from core.errors import DeviceNotConnectedError  # noqa: E402
from drivers.gamepad.mapping import GamepadConfig, axis_value  # noqa: E402

AXIS_IDS = {
    "leftx": pygame.CONTROLLER_AXIS_LEFTX,
    "lefty": pygame.CONTROLLER_AXIS_LEFTY,
    "rightx": pygame.CONTROLLER_AXIS_RIGHTX,
    "righty": pygame.CONTROLLER_AXIS_RIGHTY,
    "lefttrigger": pygame.CONTROLLER_AXIS_TRIGGERLEFT,
    "righttrigger": pygame.CONTROLLER_AXIS_TRIGGERRIGHT,
}
BUTTON_IDS = {
    "a": pygame.CONTROLLER_BUTTON_A,
    "b": pygame.CONTROLLER_BUTTON_B,
    "x": pygame.CONTROLLER_BUTTON_X,
    "y": pygame.CONTROLLER_BUTTON_Y,
    "back": pygame.CONTROLLER_BUTTON_BACK,
    "guide": pygame.CONTROLLER_BUTTON_GUIDE,
    "start": pygame.CONTROLLER_BUTTON_START,
    "leftstick": pygame.CONTROLLER_BUTTON_LEFTSTICK,
    "rightstick": pygame.CONTROLLER_BUTTON_RIGHTSTICK,
    "leftshoulder": pygame.CONTROLLER_BUTTON_LEFTSHOULDER,
    "rightshoulder": pygame.CONTROLLER_BUTTON_RIGHTSHOULDER,
    "dpup": pygame.CONTROLLER_BUTTON_DPAD_UP,
    "dpdown": pygame.CONTROLLER_BUTTON_DPAD_DOWN,
    "dpleft": pygame.CONTROLLER_BUTTON_DPAD_LEFT,
    "dpright": pygame.CONTROLLER_BUTTON_DPAD_RIGHT,
}
_HOTPLUG_EVENTS = (pygame.CONTROLLERDEVICEADDED, pygame.CONTROLLERDEVICEREMOVED)


def controller_attached() -> bool:
    """True if SDL lists a game controller (a real pad is plugged in); False if SDL cannot
    start."""
    try:
        init_sdl()
    except Exception:
        return False
    return any(sdl_controller.is_controller(i) for i in range(sdl_controller.get_count()))


def init_sdl() -> None:
    """Start the SDL parts the driver needs (idempotent; see the module doc).

    Raises ``pygame.error`` if SDL cannot start them.
    """
    os.environ.setdefault("SDL_JOYSTICK_ALLOW_BACKGROUND_EVENTS", "1")
    if not pygame.display.get_init():
        previous = os.environ.get("SDL_VIDEODRIVER")
        os.environ["SDL_VIDEODRIVER"] = previous or "dummy"
        try:
            pygame.display.init()
        finally:
            if previous is None:
                del os.environ["SDL_VIDEODRIVER"]
    sdl_controller.init()


class PygameGamepad(ContextManagedDevice):
    """An Xbox / PS4 / PS5 pad read through SDL's game-controller API.

    ``read()`` gives axes and buttons by action name as mapped in ``GamepadConfig``; axes are
    dimensionless in [-1, 1] after the dead zone (see ``drivers.gamepad.mapping``). ``clock``
    stamps the readings (``MonotonicClock`` when None). SDL calls never block.
    """

    def __init__(self, config: GamepadConfig, clock: Clock | None = None) -> None:
        self.config = config
        self.name = config.name
        self._clock = clock if clock is not None else MonotonicClock()
        self._open = False
        self._pad: sdl_controller.Controller | None = None

    @classmethod
    def from_config(cls, config: GamepadConfig, clock: Clock | None = None) -> Self:
        """Build the driver; SDL needs no transport object, so this is the constructor."""
        return cls(config, clock)

    @property
    def is_connected(self) -> bool:
        """True between ``connect()`` and ``disconnect()``, even while the pad is unplugged."""
        return self._open

    def connect(self) -> None:
        """Start SDL and open the first game controller.

        Raises ``DeviceNotConnectedError`` if SDL cannot start or no game controller is attached.
        """
        if self._open:
            return
        try:
            init_sdl()
        except pygame.error as err:
            raise DeviceNotConnectedError(
                self.name,
                f"SDL could not start its game-controller subsystem ({err}); on a machine "
                "without a display set SDL_VIDEODRIVER=dummy",
            ) from err
        pygame.event.pump()
        self._pad = self._open_first_controller()
        if self._pad is None:
            raise DeviceNotConnectedError(self.name, self._absent_message())
        self._open = True

    def disconnect(self) -> None:
        """Close the pad (idempotent, never raises on a closed driver)."""
        self._close_pad()
        self._open = False

    def read(self) -> GamepadState:
        """Pump SDL events, follow hot-plug, and return the mapped state (``t_s`` on the clock).

        While no pad is attached the state is safe: ``connected=False``, axes 0.0, buttons
        released. Raises ``DeviceNotConnectedError`` before ``connect()``.
        """
        if not self._open:
            raise DeviceNotConnectedError(self.name, "read() called before connect()")
        for event in pygame.event.get(eventtype=_HOTPLUG_EVENTS):
            if event.type == pygame.CONTROLLERDEVICEREMOVED and self._pad is not None:
                if not self._pad.attached():
                    self._close_pad()
            elif event.type == pygame.CONTROLLERDEVICEADDED and self._pad is None:
                self._pad = self._open_first_controller()
        # Drop the rest unconverted: the axes and buttons are read as state below, and pygame
        # 2.6 fails converting a JOYDEVICEREMOVED whose JOYDEVICEADDED it converted after the
        # device had gone (a plug/unplug between two reads): SystemError from a KeyError.
        pygame.event.clear(pump=False)
        t_s = self._clock.now()
        pad = self._pad
        cfg = self.config
        if pad is None:
            return GamepadState.unplugged(t_s, cfg.axes, cfg.buttons)
        return GamepadState(
            t_s=t_s,
            connected=True,
            axes={
                action: axis_value(pad.get_axis(AXIS_IDS[b.axis]), b, cfg.dead_zone)
                for action, b in cfg.axes.items()
            },
            buttons={
                action: pad.get_button(BUTTON_IDS[button]) for action, button in cfg.buttons.items()
            },
        )

    def _open_first_controller(self) -> sdl_controller.Controller | None:
        for index in range(sdl_controller.get_count()):
            if sdl_controller.is_controller(index):
                try:
                    return sdl_controller.Controller(index)
                except pygame.error as err:
                    raise DeviceNotConnectedError(
                        self.name,
                        f"SDL lists game controller {index} but cannot open it ({err}); check "
                        "read/write permission on /dev/input/event* and /dev/hidraw*",
                    ) from err
        return None

    def _close_pad(self) -> None:
        if self._pad is not None:
            self._pad.quit()
            self._pad = None

    def _absent_message(self) -> str:
        joysticks = sdl_controller.get_count()
        if joysticks:
            return (
                f"{joysticks} joystick(s) attached but SDL knows none as a game controller; "
                "add the pad's mapping to the SDL_GAMECONTROLLERCONFIG environment variable "
                "(see the SDL_GameControllerDB project)"
            )
        return (
            "no game controller attached; check the USB cable or the Bluetooth pairing, that "
            "the pad is switched on, and that this user may read /dev/input/event* "
            "(Linux group 'input')"
        )
