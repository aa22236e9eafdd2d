"""The transition table's check: a broken definition is refused when the machine is built."""

from dataclasses import replace

import pytest

from controller.insertion.definition import (
    INSERTION,
    DefinitionError,
    Edge,
    check_definition,
)
from controller.insertion.interface import Phase
from controller.insertion.machine import InsertionMachine
from controller.insertion.machine_config import MachineConfig
from core.task_geometry import HolePose, PlugGeometry
from tests.controller.insertion.world import ToyWorld


def build(definition):
    return InsertionMachine(MachineConfig(), PlugGeometry(), HolePose(), definition)


def test_the_insertion_table_passes_and_names_every_failure_reason():
    check_definition(INSERTION)
    reasons = {e.guard for e in INSERTION.edges if e.target is Phase.FAILED}
    assert reasons == {
        "timeout",
        "limit_exceeded",
        "slip",
        "contact_lost",
        "too_many_retries",
        "device_fault",
    }


def test_an_unreachable_phase_is_refused():
    edges = tuple(e for e in INSERTION.edges if e.target is not Phase.BACKOFF)
    with pytest.raises(DefinitionError, match="unreachable phases: BACKOFF"):
        build(replace(INSERTION, edges=edges))


def test_a_trap_phase_is_refused():
    # BACKOFF stays reachable from INSERT but loses every way out.
    edges = tuple(e for e in INSERTION.edges if e.source is not Phase.BACKOFF)
    with pytest.raises(DefinitionError, match=r"trap phases \(cannot reach .*\): BACKOFF$"):
        build(replace(INSERTION, edges=edges))


def test_a_terminal_phase_with_an_exit_is_refused():
    edges = (*INSERTION.edges, Edge(Phase.DONE, Phase.GRASP, "again"))
    with pytest.raises(DefinitionError, match="terminal phase DONE"):
        build(replace(INSERTION, edges=edges))


def test_an_edge_to_a_phase_outside_the_machine_is_refused():
    phases = tuple(p for p in Phase if p is not Phase.ESTOP)
    with pytest.raises(DefinitionError, match="not in the machine"):
        build(replace(INSERTION, phases=phases))


def test_the_machine_refuses_a_transition_missing_from_its_table():
    # A checked table without the grasp's exit edge to APPROACH by its guard's name.
    edges = tuple(e for e in INSERTION.edges if e.guard != "grasped_and_zeroed")
    edges += (Edge(Phase.GRASP, Phase.APPROACH, "renamed"),)
    machine = build(replace(INSERTION, edges=edges))
    world = ToyWorld()
    with pytest.raises(RuntimeError, match="GRASP -> APPROACH .grasped_and_zeroed. is not in"):
        world.run_until(machine, Phase.APPROACH, max_s=5.0)
