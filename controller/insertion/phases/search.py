"""SEARCH: drag the tilted tip along the search pattern with a preload, watching for the
hole (``search.HoleDetector``); contact lost: probe straight down (config.SearchSettings).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum
from typing import TYPE_CHECKING

import numpy as np

from controller.insertion.commands import hold, tip_command
from controller.insertion.interface import Command, FailureReason, Observation, Phase
from controller.insertion.machine_config import MachineConfig
from controller.insertion.motion import tip_position
from controller.insertion.phases.stage import Staged
from controller.insertion.search_path import HoleDetector
from core.spatial import clamp_norm, rotation_from_rpy

if TYPE_CHECKING:
    from controller.insertion.machine import InsertionMachine

_AHEAD_M = 1e-4  # the pattern's direction: toward its point this much further along


class SearchStage(Enum):
    """SEARCH's sub-stages."""

    DRAG = "drag"  # the tip along the pattern, held ``search.press_depth_m`` below contact
    PROBE = "probe"  # contact lost: the tip straight down until contact again


@dataclass(kw_only=True)
class SearchState(Staged[SearchStage]):
    """SEARCH so far (``count``: successive estimates without contact while dragging, with
    contact while probing): ``entered_t_s`` (s) when it began; ``z0_m`` the TCP height the
    preload is held from (m, B z: on entry, or where a probe touched the surface);
    ``detector`` the hole-found rule; ``v_tip`` the last tip velocity commanded (m/s, B)."""

    entered_t_s: float
    z0_m: float
    detector: HoleDetector
    v_tip: np.ndarray = field(default_factory=lambda: np.zeros(3))


def enter(obs: Observation, config: MachineConfig) -> SearchState:
    """SEARCH entered at ``obs``."""
    return SearchState(
        stage=SearchStage.DRAG,
        since_t_s=obs.t_s,
        entered_t_s=obs.t_s,
        z0_m=float(obs.arm.tcp.xyz_m[2]),
        detector=HoleDetector(config.search, config.signals.ema_alpha),
    )


def step(machine: InsertionMachine, obs: Observation, new: bool) -> Command:
    """SEARCH's command for ``obs`` (see the module doc)."""
    state, settings = machine.state(SearchState), machine.config.search
    memory = machine.memory
    memory.search_s_m += settings.speed_m_s * min(machine.tick_s, settings.max_tick_s)
    if state.stage is SearchStage.PROBE:
        return _probe(machine, state, obs, new)
    rotation = rotation_from_rpy(obs.arm.tcp.rpy_rad)
    if new:
        lost = machine.signals.magnitude < settings.contact_lost_sigma
        state.count = state.count + 1 if lost else 0
        if state.count >= settings.contact_lost_frames:
            machine.fire("lost_contact")
            state.next(SearchStage.PROBE, obs.t_s)
            return hold()
        elapsed = obs.t_s - state.entered_t_s
        fired = state.detector.update(machine.signals, rotation, state.v_tip, elapsed)
        if fired:
            if state.detector.load_reference is not None:
                memory.preload_sigma = max(state.detector.load_reference, settings.min_load_sigma)
            machine.go(obs, Phase.ALIGN, "hole_found", fired)
            return hold()
    machine.fire("drag")
    offset = machine.pattern_offset_b(memory.search_s_m)
    ahead = machine.pattern_offset_b(memory.search_s_m + _AHEAD_M) - offset
    tangent = ahead / np.linalg.norm(ahead) if np.linalg.norm(ahead) > 0 else ahead
    tip = tip_position(obs.arm.tcp, machine.plug.length_m) + machine.tip_shift_b(rotation)
    gain = machine.config.approach.pose_gain_1_s
    v_tip = np.zeros(3)
    v_tip[:2] = settings.speed_m_s * tangent[:2] + gain * (
        machine.hole_xyz[:2] + offset[:2] - tip[:2]
    )
    v_tip[:2] = clamp_norm(v_tip[:2], settings.max_speed_ratio * settings.speed_m_s)
    v_tip[2] = gain * (state.z0_m - settings.press_depth_m - obs.arm.tcp.xyz_m[2])
    state.v_tip = clamp_norm(v_tip, machine.config.approach.move_speed_m_s)
    return tip_command(
        machine.config, machine.plug, obs, state.v_tip, machine.hold_rotation(rotation)
    )


def _probe(machine: InsertionMachine, state: SearchState, obs: Observation, new: bool) -> Command:
    """SEARCH after losing contact: the tip straight down until contact again (in the
    opening: ALIGN; on the surface: drag on) or past the overtravel (contact lost)."""
    approach = machine.config.approach
    tip_z = tip_position(obs.arm.tcp, machine.plug.length_m)[2]
    if new:
        contact = machine.signals.magnitude >= approach.contact_sigma
        state.count = state.count + 1 if contact else 0
    if state.count >= approach.contact_frames:
        if tip_z <= machine.hole.z_m - machine.config.search.in_hole_depth_m:
            machine.go(obs, Phase.ALIGN, "hole_found", "probe")
        else:
            machine.fire("probe_surface")
            state.next(SearchStage.DRAG, obs.t_s)
            state.z0_m = float(obs.arm.tcp.xyz_m[2])
        return hold()
    if tip_z < machine.hole.z_m - approach.overtravel_m:
        return machine.fail(obs, FailureReason.CONTACT_LOST)
    machine.fire("probe")
    rotation = rotation_from_rpy(obs.arm.tcp.rpy_rad)
    v_tip = np.array([0.0, 0.0, -approach.descend_speed_m_s])
    return tip_command(machine.config, machine.plug, obs, v_tip, machine.hold_rotation(rotation))
