"""An SDL virtual game controller that pygame sees as a real, hot-pluggable device.

How it works (checked with pygame 2.6.1 and its bundled SDL 2.28.4 on Linux, headless with
``SDL_VIDEODRIVER=dummy``):

- The calls go through ctypes into the *same* SDL library instance pygame has loaded (its
  wheel bundles it, e.g. ``site-packages/pygame.libs/libSDL2-2-<hash>.so...``). On Linux the
  path is read from ``/proc/self/maps``; elsewhere the pygame folders are searched. The
  library is accepted only if ``SDL_WasInit`` reports the joystick subsystem that pygame
  started, which a second copy of SDL would not.
- ``SDL_JoystickAttachVirtual(SDL_JOYSTICK_TYPE_GAMECONTROLLER, 6, 15, 0)`` (SDL >= 2.0.14)
  is listed by ``pygame._sdl2.controller.is_controller`` with no mapping added: SDL builds one
  itself for virtual game controllers (name "Virtual Controller"), binding joystick axis i and
  button i to the i-th ``SDL_GameControllerAxis`` / ``SDL_GameControllerButton``
  (``a:b0, b:b1, ..., dpright:b14, leftx:a0, ..., righttrigger:a5``).
- A generic virtual joystick (``SDL_JOYSTICK_TYPE_UNKNOWN``) is *not* a game controller until
  a mapping for its GUID is added with ``SDL_GameControllerAddMapping`` (tried: that works
  too); ``VirtualJoystick(game_controller=False)`` gives such a device for the "joystick but
  no mapping" case.
- Values are set on an ``SDL_Joystick*`` the helper opens itself
  (``SDL_JoystickSetVirtualAxis/Button``); they reach readers at the next event pump.
  Trigger axes are full range at the joystick level (released = -32768); SDL's controller
  layer maps them to 0..32767, so ``set_axis`` takes controller values and converts them.
- Attaching posts CONTROLLERDEVICEADDED; ``SDL_JoystickDetachVirtual`` posts axis-zero and
  button-up events, then CONTROLLERDEVICEREMOVED, like a pulled cable.
- Found with it: pygame 2.6.1's ``pygame.event.get()`` raises SystemError (a KeyError
  inside) when a device is attached and detached between two calls; ``PygameGamepad.read()``
  therefore converts only the controller hot-plug events.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import glob
from pathlib import Path
from types import TracebackType
from typing import Self

import pygame

SDL_INIT_JOYSTICK = 0x200
SDL_JOYSTICK_TYPE_UNKNOWN = 0
SDL_JOYSTICK_TYPE_GAMECONTROLLER = 1

# Layout of SDL's automatic mapping for a virtual game controller: joystick axis / button i is
# the controller axis / button of the same enum index.
VIRTUAL_AXES = ("leftx", "lefty", "rightx", "righty", "lefttrigger", "righttrigger")
VIRTUAL_BUTTONS = (
    "a", "b", "x", "y", "back", "guide", "start", "leftstick", "rightstick",
    "leftshoulder", "rightshoulder", "dpup", "dpdown", "dpleft", "dpright",
)  # fmt: skip
TRIGGERS = ("lefttrigger", "righttrigger")


class _Version(ctypes.Structure):
    _fields_ = [("major", ctypes.c_uint8), ("minor", ctypes.c_uint8), ("patch", ctypes.c_uint8)]


def _candidate_paths() -> list[str]:
    maps = Path("/proc/self/maps")
    if maps.exists():
        lines = maps.read_text().splitlines()
        loaded = {line.split()[-1] for line in lines if "/libSDL2-2" in line}
        if loaded:
            return sorted(loaded)
    package = Path(pygame.__file__).parent
    patterns = ["libSDL2-2*.so*", "libSDL2-2*.dylib", "SDL2.dll"]
    folders = [package, package.parent / "pygame.libs", package / ".dylibs"]
    found = [p for f in folders for pattern in patterns for p in glob.glob(str(f / pattern))]
    system = ctypes.util.find_library("SDL2")
    return found + ([system] if system else [])


def load_pygame_sdl() -> ctypes.CDLL:
    """The SDL2 library pygame uses, with the virtual-joystick functions typed.

    Call after pygame's joystick subsystem has started (e.g. after ``init_sdl()``). Raises
    RuntimeError if no candidate is pygame's own instance or SDL is older than 2.0.14.
    """
    for path in _candidate_paths():
        lib = ctypes.CDLL(path)  # an already-loaded path gives pygame's own instance
        if lib.SDL_WasInit(SDL_INIT_JOYSTICK):
            break
    else:
        raise RuntimeError("pygame's SDL2 library not found among the loaded libraries")
    version = _Version()
    lib.SDL_GetVersion(ctypes.byref(version))
    if (version.major, version.minor, version.patch) < (2, 0, 14):
        found = f"{version.major}.{version.minor}.{version.patch}"
        raise RuntimeError(f"SDL {found} has no virtual joysticks (needs 2.0.14)")
    lib.SDL_GetError.restype = ctypes.c_char_p
    lib.SDL_JoystickAttachVirtual.argtypes = [ctypes.c_int] * 4
    lib.SDL_JoystickDetachVirtual.argtypes = [ctypes.c_int]
    lib.SDL_JoystickOpen.argtypes = [ctypes.c_int]
    lib.SDL_JoystickOpen.restype = ctypes.c_void_p
    lib.SDL_JoystickClose.argtypes = [ctypes.c_void_p]
    lib.SDL_JoystickInstanceID.argtypes = [ctypes.c_void_p]
    lib.SDL_JoystickGetDeviceInstanceID.argtypes = [ctypes.c_int]
    lib.SDL_JoystickSetVirtualAxis.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_int16]
    lib.SDL_JoystickSetVirtualButton.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_uint8]
    return lib


def pygame_sdl_or_skip() -> ctypes.CDLL:
    """Start pygame's SDL (``drivers.gamepad.pad.init_sdl``) and return its library for
    virtual devices; skip the test if a real joystick is attached (it would be opened
    first)."""
    import pytest
    from pygame._sdl2 import controller as sdl_controller

    from drivers.gamepad.pad import init_sdl

    # A pygame.quit() earlier in this process (the view's tests) stops SDL's joystick
    # subsystem under pygame's controller module, which stays started, so init_sdl() alone
    # would not start it again (the driver never meets this: the view has its own process).
    # The controller module is stopped first, so that init_sdl() starts SDL as a fresh
    # process has it; in a fresh process stopping it does nothing.
    sdl_controller.quit()
    init_sdl()
    lib = load_pygame_sdl()
    if sdl_controller.get_count():
        pytest.skip("a real joystick is attached; unplug it to run the virtual-device tests")
    return lib


class VirtualJoystick:
    """One SDL virtual device, attached on ``attach()`` (or ``with``), removed on ``detach()``.

    ``game_controller=True`` gives the 6-axis, 15-button game controller SDL maps itself;
    ``False`` a generic 2-axis, 2-button joystick that SDL does not know as a controller.
    """

    def __init__(self, sdl: ctypes.CDLL, game_controller: bool = True) -> None:
        self._sdl = sdl
        self._game_controller = game_controller
        self._joystick: int | None = None  # SDL_Joystick* opened by the helper

    @property
    def attached(self) -> bool:
        return self._joystick is not None

    def attach(self) -> None:
        """Plug the device in (CONTROLLERDEVICEADDED at the next pump)."""
        if self._game_controller:
            shape = (SDL_JOYSTICK_TYPE_GAMECONTROLLER, len(VIRTUAL_AXES), len(VIRTUAL_BUTTONS), 0)
        else:
            shape = (SDL_JOYSTICK_TYPE_UNKNOWN, 2, 2, 0)
        index = self._sdl.SDL_JoystickAttachVirtual(*shape)
        if index < 0:
            raise RuntimeError(f"SDL_JoystickAttachVirtual: {self._sdl.SDL_GetError().decode()}")
        joystick = self._sdl.SDL_JoystickOpen(index)
        if not joystick:
            raise RuntimeError(f"SDL_JoystickOpen: {self._sdl.SDL_GetError().decode()}")
        self._joystick = joystick

    def detach(self) -> None:
        """Pull the cable: the device disappears (idempotent)."""
        if self._joystick is None:
            return
        instance = self._sdl.SDL_JoystickInstanceID(self._joystick)
        self._sdl.SDL_JoystickClose(self._joystick)
        self._joystick = None
        # Device indices shift as devices come and go; find ours by its instance id.
        for index in range(self._sdl.SDL_NumJoysticks()):
            if self._sdl.SDL_JoystickGetDeviceInstanceID(index) == instance:
                self._check(self._sdl.SDL_JoystickDetachVirtual(index))
                return

    def set_axis(self, axis: str, value: int) -> None:
        """Move a controller axis: sticks -32768..32767 (y down), triggers 0..32767."""
        # Triggers are full range at the joystick level; SDL maps -32768..32767 to 0..32767.
        raw = round(value * 65535 / 32767) - 32768 if axis in TRIGGERS else value
        self._check(
            self._sdl.SDL_JoystickSetVirtualAxis(self._handle(), VIRTUAL_AXES.index(axis), raw)
        )

    def set_button(self, button: str, pressed: bool) -> None:
        self._check(
            self._sdl.SDL_JoystickSetVirtualButton(
                self._handle(), VIRTUAL_BUTTONS.index(button), int(pressed)
            )
        )

    def __enter__(self) -> Self:
        self.attach()
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.detach()

    def _handle(self) -> int:
        if self._joystick is None:
            raise RuntimeError("virtual joystick is not attached")
        return self._joystick

    def _check(self, result: int) -> None:
        if result < 0:
            raise RuntimeError(self._sdl.SDL_GetError().decode())
