"""The machine's sub-stages: named by each phase's Enum, listed in the checked definition,
recorded with every tick; the task file's named factors are range-checked."""

from dataclasses import replace
from enum import Enum

import pytest

from controller.insertion.definition import INSERTION, DefinitionError, check_definition
from controller.insertion.interface import Phase
from controller.insertion.machine import InsertionMachine
from controller.insertion.machine_config import MachineConfig
from controller.insertion.phases import (
    align,
    approach,
    backoff,
    grasp,
    insert,
    overrides,
    release,
    retract,
    search,
)
from core.config import ConfigError
from core.task_geometry import HolePose, PlugGeometry
from tests.controller.insertion.test_config import example, load_edited
from tests.controller.insertion.world import ToyWorld, make_machine, toy_config

STAGE_ENUMS = (
    grasp.GraspStage, approach.ApproachStage, search.SearchStage, align.AlignStage,
    insert.InsertStage, backoff.BackoffStage, release.ReleaseStage, retract.RetractStage,
    overrides.TeleopStage, overrides.EstopStage, overrides.TerminalStage,
)  # fmt: skip


def test_every_sub_stage_of_every_phase_module_is_in_the_definition():
    listed = {stage for stages in INSERTION.stages.values() for stage in stages}
    for kind in STAGE_ENUMS:
        for stage in kind:
            assert stage in listed, f"{kind.__name__}.{stage.name}"
    assert set(INSERTION.stages) == set(Phase)


def _without(phase: Phase, stage: Enum):
    stages = dict(INSERTION.stages)
    stages[phase] = tuple(s for s in stages[phase] if s is not stage)
    return replace(INSERTION, stages=stages)


def test_a_definition_missing_a_sub_stage_is_refused():
    with pytest.raises(DefinitionError, match="phase ALIGN: .* missing WIDTH"):
        check_definition(_without(Phase.ALIGN, align.AlignStage.WIDTH))
    stages = {p: s for p, s in INSERTION.stages.items() if p is not Phase.SEARCH}
    with pytest.raises(DefinitionError, match="phase SEARCH lists no sub-stages"):
        check_definition(replace(INSERTION, stages=stages))
    mixed = dict(INSERTION.stages)
    mixed[Phase.BACKOFF] = (backoff.BackoffStage.LIFT, retract.RetractStage.LIFT)
    with pytest.raises(DefinitionError, match="phase BACKOFF: sub-stages of several enums"):
        check_definition(replace(INSERTION, stages=mixed))


def test_every_tick_records_its_phase_sub_stage_and_rule():
    world = ToyWorld()
    machine = make_machine(world, toy_config())
    commands = []
    while machine.phase is not Phase.DONE and world.t_s < 60.0:
        commands.append(world.step(machine))
    assert machine.phase is Phase.DONE
    assert (commands[-1].stage, commands[-1].rule) == ("retract.lift", "retract.retracted")
    commands.append(world.step(machine))
    listed = {f"{p.value}.{s.value}" for p, stages in INSERTION.stages.items() for s in stages}
    assert all(c.stage in listed for c in commands), {c.stage for c in commands} - listed
    assert all(c.rule and c.rule.split(".")[0] == c.stage.split(".")[0] for c in commands)
    seen = {c.stage for c in commands}
    assert {"grasp.capture", "approach.descend", "search.drag", "align.seek"} <= seen
    assert commands[-1].stage == "done.hold" and commands[-1].rule == "done.hold"


def test_a_sub_stage_its_phase_does_not_list_is_refused_when_recorded():
    swapped = dict(INSERTION.stages)
    swapped[Phase.GRASP], swapped[Phase.APPROACH] = swapped[Phase.APPROACH], swapped[Phase.GRASP]
    definition = replace(INSERTION, stages=swapped)
    check_definition(definition)  # each phase lists one whole enum, but not its own
    machine = InsertionMachine(MachineConfig(), PlugGeometry(), HolePose(), definition)
    with pytest.raises(RuntimeError, match="sub-stage GRASP.CAPTURE is not in"):
        ToyWorld().step(machine)


@pytest.mark.parametrize(
    ("where", "value", "expected"),
    [
        ("machine.align.aligned_load_ratio", -0.5, "expected a number in [0.0, 10.0]"),
        ("machine.align.entering_ratio", 1.5, "expected a number in [0.0, 1.0]"),
        ("machine.insert.stall_load_ratio", 2.0, "expected a number in [0.0, 1.0]"),
        ("machine.insert.give_way_ratio", -1.0, "expected a number in [0.0, 1.0]"),
        ("machine.insert.progress_m", 0.5, "expected a number in [1e-06, 0.01]"),
        ("machine.search.max_speed_ratio", 0.5, "expected a number in [1.0, 10.0]"),
        ("machine.search.max_tick_s", 0.0, "expected a number in [0.001, 10.0]"),
        ("machine.search.steady_speed_ratio", 2.0, "expected a number in [0.0, 1.0]"),
        ("machine.search.steady_cosine", 1.5, "expected a number in [0.0, 1.0]"),
        ("machine.search.min_load_sigma", 0.0, "expected a number in [0.01, 10000.0]"),
    ],
)
def test_a_bad_named_factor_is_one_line_naming_its_key(where, value, expected, tmp_path):
    data = example()
    *parents, key = where.split(".")
    node = data
    for name in parents:
        node = node[name]
    node[key] = value
    with pytest.raises(ConfigError) as error:
        load_edited(data, tmp_path)
    message = str(error.value)
    assert f"key '{where}': {expected}, got {value}" in message and "\n" not in message
