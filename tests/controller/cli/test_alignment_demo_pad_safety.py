"""Deadman, e-stop and unplug in the demo, with the real gamepad driver on an SDL virtual
game controller (pygame sees it as a plugged-in pad) driving the simulated world: the demo's
own pad path (``demo_cli._pad_preparation`` without a script puts the real pad in the world).
The joystick is moved from the loop's observer, so each change is seen at the next tick."""

import pytest

from controller.cli import alignment_demo as demo_cli
from controller.cli.alignment_demo import TELEOP_CONTROLLER, _pad_preparation
from controller.insertion import Phase
from controller.run import load_task, run_task
from tests.drivers.virtual_joystick import VirtualJoystick, pygame_sdl_or_skip

FULL = 32767


@pytest.fixture(scope="module")
def sdl():
    return pygame_sdl_or_skip()


def script_for(joystick):
    """(time s, action) steps: a stick without the deadman, with it, the e-stop held,
    released, moved, acknowledged, then an unplug during motion."""
    steps = [
        (3.0, lambda: joystick.set_axis("leftx", -FULL)),  # vy = +1, deadman released
        (4.0, lambda: joystick.set_button("leftshoulder", True)),  # deadman held: moves
        (5.0, lambda: joystick.set_axis("leftx", 0)),
        (5.2, lambda: joystick.set_button("b", True)),  # e-stop pressed
        (5.5, lambda: joystick.set_button("b", False)),  # released, not acknowledged
        (5.6, lambda: joystick.set_axis("leftx", -FULL)),  # the stick is ignored in ESTOP
        (6.0, lambda: joystick.set_button("back", True)),  # acknowledged
        (6.2, lambda: joystick.set_button("back", False)),
        (6.5, joystick.detach),  # unplugged while moving
    ]
    return steps


def test_deadman_estop_and_unplug_hold_on_a_virtual_joystick(sdl):
    task = load_task("usb_c", [*demo_cli.demo_overrides(demo_cli.build_parser().parse_args(
        ["--no-view", "--fast", "--out", "unused"])), "machine.timeouts.total_s=20"])  # fmt: skip
    table = demo_cli.controller_table([])
    joystick = VirtualJoystick(sdl)
    joystick.attach()
    steps = script_for(joystick)
    ticks = []

    def observe(tick):
        ticks.append(tick)
        while steps and tick.timing.start_s >= steps[0][0]:
            steps.pop(0)[1]()

    try:
        outcome = run_task(task, TELEOP_CONTROLLER, 0, controllers=table,
                           prepare=_pad_preparation(task, None), observers=[observe])  # fmt: skip
    finally:
        joystick.detach()

    def during(a, b):
        return [t for t in ticks if a + 0.05 <= t.timing.start_s < b]

    no_deadman = during(3.0, 4.0)
    assert all(not t.observation.teleop.deadman and not t.observation.teleop.in_control
               for t in no_deadman)  # fmt: skip
    assert all(t.command.twist.linear_m_s == (0.0, 0.0, 0.0) for t in no_deadman)
    y = [t.observation.arm.tcp.xyz_m[1] for t in no_deadman]
    assert max(y) - min(y) < 1e-6  # the arm did not move
    moving = during(4.0, 5.0)
    assert all(t.observation.teleop.in_control for t in moving)
    assert moving[-1].observation.arm.tcp.xyz_m[1] - moving[0].observation.arm.tcp.xyz_m[1] > 0.01
    latched = during(5.2, 6.0)
    assert all(t.phase is Phase.ESTOP for t in latched)
    assert all(t.command.twist.linear_m_s == (0.0, 0.0, 0.0) for t in latched)
    assert all(t.phase is Phase.TELEOP for t in during(6.0, 6.5))
    assert outcome.loop.reason == "fault" and "gamepad" in outcome.loop.message
    last = ticks[-1]
    assert last.fault is not None and not last.observation.teleop.connected
    connected = [t for t in ticks if t.observation.teleop.connected]
    assert ticks[-2] is connected[-1]  # the trip came at the first tick without the pad
    assert last.timing.start_s - connected[-1].timing.start_s <= task.config.loop.period_s + 1e-9
    assert connected[-1].command.twist.linear_m_s[1] > 0  # it was moving when unplugged
