"""The insertion machine's transition table and sub-stages, as data, and their check.

Each ``Edge`` says that ``source`` may go to ``target`` when the guard ``guard`` holds; the
guard's name is the reason the machine records (for FAILED, a ``FailureReason`` value). The
machine refuses a transition that is not in its table, and the table is checked when the
machine is built: every phase reachable from the initial one, none a trap (each non-terminal
phase can reach a terminal one), terminal phases without outgoing edges. Each phase lists
its sub-stages (``stages``): every member of the Enum its module (``phases/``) names them
by, and the machine refuses to be in a sub-stage that is not listed.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from enum import Enum

from controller.insertion.interface import FailureReason, Phase
from controller.insertion.phases.align import AlignStage
from controller.insertion.phases.approach import ApproachStage
from controller.insertion.phases.backoff import BackoffStage
from controller.insertion.phases.feel import FeelStage
from controller.insertion.phases.grasp import GraspStage
from controller.insertion.phases.insert import InsertStage
from controller.insertion.phases.overrides import EstopStage, TeleopStage, TerminalStage
from controller.insertion.phases.release import ReleaseStage
from controller.insertion.phases.retract import RetractStage
from controller.insertion.phases.search import SearchStage

AUTONOMOUS = (
    Phase.GRASP,
    Phase.APPROACH,
    Phase.FEEL,
    Phase.SEARCH,
    Phase.ALIGN,
    Phase.INSERT,
    Phase.BACKOFF,
    Phase.RELEASE,
    Phase.RETRACT,
)
TERMINAL = (Phase.DONE, Phase.FAILED)
# Where autonomy resumes after TELEOP or an acknowledged ESTOP (machine.py decides which).
RESUMABLE = (Phase.GRASP, Phase.APPROACH, Phase.SEARCH, Phase.ALIGN, Phase.RETRACT)
# Phases in which the plug touches the board or the opening.
IN_CONTACT = (Phase.FEEL, Phase.SEARCH, Phase.ALIGN, Phase.INSERT, Phase.BACKOFF)

F = FailureReason


class DefinitionError(ValueError):
    """The definition is malformed: an unreachable phase, a trap, a terminal exit, a phase
    whose sub-stages are not listed, or not all of them."""


@dataclass(frozen=True)
class Edge:
    """``source`` may go to ``target`` when the guard ``guard`` holds."""

    source: Phase
    target: Phase
    guard: str


@dataclass(frozen=True)
class Definition:
    """A machine's phases, where it starts, where it ends, its edges, and each phase's
    sub-stages (none listed: a machine without named sub-stages, such as the blind
    baseline)."""

    phases: tuple[Phase, ...]
    initial: Phase
    terminal: tuple[Phase, ...]
    edges: tuple[Edge, ...]
    stages: Mapping[Phase, tuple[Enum, ...]] = field(default_factory=dict)

    def allows(self, source: Phase, target: Phase, guard: str) -> bool:
        """True if the table has the edge ``source -> target`` under ``guard``."""
        return Edge(source, target, guard) in self.edges


def _edges(sources: Iterable[Phase], target: Phase, guards: Iterable[str]) -> list[Edge]:
    guards = tuple(guards)
    return [Edge(s, target, g) for s in sources for g in guards]


def _insertion_edges() -> tuple[Edge, ...]:
    edges = [
        Edge(Phase.GRASP, Phase.APPROACH, "grasped_and_zeroed"),
        Edge(Phase.APPROACH, Phase.FEEL, "first_contact"),
        Edge(Phase.FEEL, Phase.APPROACH, "grasp_felt"),
        Edge(Phase.APPROACH, Phase.SEARCH, "surface_contact"),
        Edge(Phase.SEARCH, Phase.ALIGN, "hole_found"),
        Edge(Phase.SEARCH, Phase.BACKOFF, "search_timeout"),
        Edge(Phase.ALIGN, Phase.INSERT, "aligned"),
        Edge(Phase.ALIGN, Phase.BACKOFF, "no_wall"),
        Edge(Phase.ALIGN, Phase.BACKOFF, "not_entered"),
        Edge(Phase.ALIGN, Phase.BACKOFF, "align_timeout"),
        Edge(Phase.INSERT, Phase.BACKOFF, "jam"),
        Edge(Phase.INSERT, Phase.BACKOFF, "not_engaged"),
        Edge(Phase.INSERT, Phase.RELEASE, "depth_reached"),
        Edge(Phase.BACKOFF, Phase.ALIGN, "backed_off"),
        Edge(Phase.BACKOFF, Phase.APPROACH, "search_again"),
        Edge(Phase.RELEASE, Phase.RETRACT, "released"),
        Edge(Phase.RETRACT, Phase.DONE, "retracted"),
    ]
    holding = (Phase.APPROACH, Phase.FEEL, Phase.SEARCH, Phase.ALIGN, Phase.INSERT, Phase.BACKOFF)
    edges += _edges(holding, Phase.GRASP, ["slip_regrasp"])
    edges += _edges(AUTONOMOUS, Phase.FAILED, [F.TIMEOUT.value, F.DEVICE_FAULT.value])
    edges += _edges(holding, Phase.FAILED, [F.SLIP.value, F.LIMIT_EXCEEDED.value])
    edges += _edges(holding, Phase.FAILED, [F.TOO_MANY_RETRIES.value])
    edges += _edges((Phase.SEARCH,), Phase.FAILED, [F.CONTACT_LOST.value])
    edges += _edges(AUTONOMOUS, Phase.TELEOP, ["operator_takeover"])
    edges += _edges((Phase.TELEOP,), Phase.FAILED, [F.DEVICE_FAULT.value])
    edges += _edges((Phase.TELEOP,), Phase.ESTOP, ["estop"])
    edges += [Edge(Phase.TELEOP, p, "hand_back") for p in RESUMABLE]
    edges += _edges(AUTONOMOUS, Phase.ESTOP, ["estop"])
    edges += [Edge(Phase.ESTOP, p, "estop_acknowledged") for p in (*RESUMABLE, Phase.TELEOP)]
    edges += _edges((Phase.ESTOP,), Phase.FAILED, [F.DEVICE_FAULT.value])
    return tuple(edges)


_STAGES: dict[Phase, tuple[Enum, ...]] = {
    Phase.GRASP: (
        GraspStage.START, GraspStage.LIFT, GraspStage.OPEN, GraspStage.CAPTURE,
        GraspStage.CLOSE, GraspStage.SETTLE, GraspStage.ZERO,
    ),
    Phase.APPROACH: (ApproachStage.POSE, ApproachStage.DESCEND),
    Phase.FEEL: (FeelStage.PRESS, FeelStage.ROCK, FeelStage.ROCK_BACK, FeelStage.LIFT),
    Phase.SEARCH: (SearchStage.DRAG, SearchStage.PROBE),
    Phase.ALIGN: (
        AlignStage.START, AlignStage.SEEK, AlignStage.TURN, AlignStage.WIDTH, AlignStage.YAW,
        AlignStage.SERVO,
    ),
    Phase.INSERT: (InsertStage.START, InsertStage.PRESS, InsertStage.PUSH),
    Phase.BACKOFF: (BackoffStage.LIFT,),
    Phase.RELEASE: (ReleaseStage.OPEN, ReleaseStage.OPENING),
    Phase.RETRACT: (RetractStage.LIFT,),
    Phase.DONE: (TerminalStage.HOLD,),
    Phase.FAILED: (TerminalStage.HOLD,),
    Phase.TELEOP: (TeleopStage.OPERATOR,),
    Phase.ESTOP: (EstopStage.HOLD,),
}  # fmt: skip

INSERTION = Definition(
    phases=tuple(Phase),
    initial=Phase.GRASP,
    terminal=TERMINAL,
    edges=_insertion_edges(),
    stages=_STAGES,
)


def check_definition(definition: Definition) -> None:
    """Raise DefinitionError unless every edge joins known phases, terminal phases have no
    outgoing edge, every phase is reachable from the initial one, every non-terminal
    phase can reach a terminal one, and, if the definition lists sub-stages, every phase
    lists its own: each member of one Enum, once."""
    known = set(definition.phases)
    if definition.initial not in known or not set(definition.terminal) <= known:
        raise DefinitionError("the initial and terminal phases must be among the phases")
    for edge in definition.edges:
        if edge.source not in known or edge.target not in known:
            raise DefinitionError(f"edge {edge} joins a phase that is not in the machine")
        if edge.source in definition.terminal:
            raise DefinitionError(f"terminal phase {edge.source.name} has an outgoing edge")
    forward = _closure({definition.initial}, definition.edges, reverse=False)
    unreachable = [p.name for p in definition.phases if p not in forward]
    if unreachable:
        raise DefinitionError(f"unreachable phases: {', '.join(unreachable)}")
    backward = _closure(set(definition.terminal), definition.edges, reverse=True)
    traps = [p.name for p in definition.phases if p not in backward]
    if traps:
        raise DefinitionError(f"trap phases (cannot reach a terminal phase): {', '.join(traps)}")
    _check_stages(definition)


def _check_stages(definition: Definition) -> None:
    """Every phase of ``definition`` lists its sub-stages, if any does: each member of one
    Enum, once; none listed for a phase outside the machine."""
    if not definition.stages:
        return
    outside = [p.name for p in definition.stages if p not in definition.phases]
    if outside:
        raise DefinitionError(f"sub-stages of phases not in the machine: {', '.join(outside)}")
    for phase in definition.phases:
        stages = definition.stages.get(phase, ())
        if not stages:
            raise DefinitionError(f"phase {phase.name} lists no sub-stages")
        kinds = {type(stage) for stage in stages}
        if len(kinds) > 1:
            raise DefinitionError(f"phase {phase.name}: sub-stages of several enums")
        missing = [s.name for s in type(stages[0]) if s not in stages]
        if missing or len(set(stages)) != len(stages):
            raise DefinitionError(
                f"phase {phase.name}: expected each sub-stage of {type(stages[0]).__name__} "
                f"once, missing {', '.join(missing) or 'none'}"
            )


def _closure(start: set[Phase], edges: tuple[Edge, ...], reverse: bool) -> set[Phase]:
    """The phases reachable from ``start`` along ``edges`` (against them with ``reverse``)."""
    seen = set(start)
    frontier = list(start)
    while frontier:
        phase = frontier.pop()
        for edge in edges:
            here, there = (edge.target, edge.source) if reverse else (edge.source, edge.target)
            if here is phase and there not in seen:
                seen.add(there)
                frontier.append(there)
    return seen
