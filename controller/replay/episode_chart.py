"""An episode's chart: the trial summary's chart (controller/replay/trial_chart.py) drawn
from the episode's streams (torques with the phase bands, the commands, and the truth where
the episode has it)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import yaml

from controller.episode import Episode
from controller.replay import episode_streams
from controller.replay.trial_chart import (
    TORQUES,
    TrialSeries,
    chart_title,
    draw_trial_chart,
    insertion_force_text,
    result_text,
)

TICK_TOLERANCE_S = 1e-9
"""An estimate logged at a tick's own time is the one that tick saw."""


def episode_series(episode: Episode) -> TrialSeries:
    """The chart's series of ``episode``: ticks from ``/loop/tick`` and ``/control/command``,
    torques from ``/tactile/wrench`` at tick time as the trial's chart draws them (each tick
    from the first estimate on, with the newest estimate made at or before it: the one the
    machine saw), the truth from ``/sim/``."""
    ticks = episode_streams.ticks(episode)
    found = episode_streams.estimates(episode)
    torques = np.column_stack([found.column(axis) for axis in TORQUES]).reshape(-1, 3)
    held = np.searchsorted(found.tick_t_s, ticks.t_s + TICK_TOLERANCE_S, side="right") - 1
    seen = held >= 0
    truth = episode_streams.truth(episode)
    return TrialSeries(
        ticks.t_s,
        ticks.phase,
        ticks.t_s[seen],
        torques[held[seen]],
        ticks.t_s,
        ticks.twist,
        None if truth is None else truth.chart,
        found.calibrated,
    )


def episode_title(episode: Episode) -> str:
    """The trial chart's title from the episode's metadata: how the trial ended (its
    result, when a trial tool wrote one, with the plug's true insertion force as
    summary.png has it), else how the loop ended."""
    info = episode.info
    outcome = episode.outcome
    forces = ""
    if outcome is None:
        ended = "no outcome (the run did not finish its file)"
    else:
        try:
            result = json.loads(outcome.get("result") or "null")
        except json.JSONDecodeError:
            result = None
        if isinstance(result, dict) and "success" in result:
            ended = result_text(bool(result["success"]), result.get("failure_reason"))
            forces = insertion_force_text(
                result.get("max_insertion_force_n"), result.get("p99_insertion_force_n")
            )
        else:
            ended = outcome.get("reason", "?")
    return chart_title(info.get("task"), info.get("seed"), info.get("controller"), ended) + forces


def write_episode_chart(episode: Episode, path: Path) -> None:
    """Draw ``episode``'s chart to the PNG ``path`` (atomically)."""
    task = yaml.safe_load(episode.attachments.get("task.yaml", b"")) or {}
    limit = task.get("contact_force_limit_n") if isinstance(task, dict) else None
    draw_trial_chart(episode_series(episode), path, episode_title(episode), limit)
