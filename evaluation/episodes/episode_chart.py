"""An episode's chart: the trial summary's chart (evaluation/trials/trial_chart.py) drawn
from the episode's streams (torques with the phase bands, the commands, and the truth where
the episode has it)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from controller.episode import Episode
from evaluation.episodes import episode_streams
from evaluation.trials.trial_chart import TORQUES, TrialSeries, draw_trial_chart


def episode_series(episode: Episode) -> TrialSeries:
    """The chart's series of ``episode``: ticks from ``/loop/tick`` and ``/control/command``,
    torques from ``/tactile/wrench`` at their frames' times, the truth from ``/sim/``."""
    ticks = episode_streams.ticks(episode)
    found = episode_streams.estimates(episode)
    torques = np.column_stack([found.column(axis) for axis in TORQUES]).reshape(-1, 3)
    truth = episode_streams.truth(episode)
    return TrialSeries(
        ticks.t_s,
        ticks.phase,
        found.t_s,
        torques,
        ticks.t_s,
        ticks.twist,
        None if truth is None else truth.chart,
    )


def episode_title(episode: Episode) -> str:
    """``TASK seed N (CONTROLLER): OUTCOME`` from the episode's metadata."""
    info = episode.info
    outcome = episode.outcome
    if outcome is None:
        ended = "no outcome (the run did not finish writing)"
    else:
        ended = outcome.get("reason", "?")
        if outcome.get("message") and outcome.get("message") != ended:
            ended += f": {outcome['message']}"
    return f"{info.get('task', '?')} seed {info.get('seed', '?')} ({info.get('controller', '?')}): {ended}"


def write_episode_chart(episode: Episode, path: Path) -> None:
    """Draw ``episode``'s chart to the PNG ``path`` (atomically)."""
    draw_trial_chart(episode_series(episode), path, episode_title(episode))
