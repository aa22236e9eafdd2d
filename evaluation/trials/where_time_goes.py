"""Where a batch's trials spend their time, rule by rule, and where its failures end
(``python -m evaluation where_time_goes OUT``).

OUT is a ``run_trials --records`` folder (its ``records/<controller>-<seed>/``) or one
trial's record (``run_trial --out``). Each record's ``trial.json`` and ``ticks.jsonl``
(controller/run/record.py) are read; no trial runs and nothing is written.

* **The trials that inserted**, per controller: the simulated seconds each phase, and each
  rule within it (the tick's ``rule``: what decided its command), held the command from the
  first tick up to the time to insert, as a mean per trial and the share of the mean time
  to insert. A tick lasts until the next one (the last, one loop period). Rules under
  ``--least`` seconds a trial are summed into their phase's ``other``.
* **The failures**, per controller: how many ended in each (phase, reason), the phase being
  the one the FAILED transition left, and how many of those never found the hole (no
  transition under one of ``FOUND``: the align machine's find, the spiral's catch or fall).
"""

from __future__ import annotations

import argparse
import json
from collections import Counter, defaultdict
from collections.abc import Iterable
from dataclasses import dataclass, field
from itertools import pairwise
from pathlib import Path
from statistics import median

from controller.cli.support import ToolError, number, run_tool
from core.subcommands import job_prog
from evaluation.trials.records import RECORDS

TRIAL_NAME = "trial.json"
TICKS_NAME = "ticks.jsonl"

#: the guards under which a machine has found the opening: the align machine's, the press
#: spiral's catch and its plug gone in on the way down
FOUND = ("hole_found", "caught", "fell_in")


@dataclass
class RuleTimes:
    """One controller's trials: ``seconds[(phase, rule)]`` summed over the inserted ones
    (``inserted`` of them, ``time_to_insert_s`` their summed times); ``endings[(phase,
    reason)]`` the failures' count, ``unfound`` those of them that never found the hole."""

    inserted: int = 0
    time_to_insert_s: float = 0.0
    seconds: defaultdict[tuple[str, str], float] = field(default_factory=lambda: defaultdict(float))
    endings: Counter[tuple[str, str]] = field(default_factory=Counter)
    unfound: Counter[tuple[str, str]] = field(default_factory=Counter)


def record_folders(out: Path) -> list[Path]:
    """The trial records in ``out``: itself, or its ``records/`` folders (hidden unfinished
    ones left out)."""
    if (out / TRIAL_NAME).is_file():
        return [out]
    folders = sorted(p.parent for p in (out / RECORDS).glob(f"[!.]*/{TRIAL_NAME}"))
    if not folders:
        raise ToolError(
            f"'{out}' holds no {TRIAL_NAME} nor {RECORDS}/<controller>-<seed>/{TRIAL_NAME}; "
            "expected a run_trial --out folder or a run_trials --records output folder"
        )
    return folders


def _read_json(path: Path) -> dict:
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ToolError(f"'{path}': not a readable JSON trial file ({exc})") from None


def _ticks(path: Path) -> list[tuple[float, str, str]]:
    """(t_s, phase, rule) of every tick in ``path``."""
    rows = []
    try:
        with path.open(encoding="utf-8") as lines:
            for line in lines:
                tick = json.loads(line)
                rows.append((float(tick["t_s"]), str(tick["phase"]), str(tick["rule"])))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError, KeyError, TypeError) as exc:
        raise ToolError(
            f"'{path}': not a trial's tick log (line {len(rows) + 1}: {exc}); expected one "
            "JSON object with t_s, phase and rule per line"
        ) from None
    return rows


def tick_seconds(
    ticks: list[tuple[float, str, str]], until_s: float
) -> dict[tuple[str, str], float]:
    """Seconds per (phase, rule) from the ticks before ``until_s`` (each lasting until the
    next tick; the last one the median period)."""
    times = [t for t, _, _ in ticks]
    last = median(b - a for a, b in pairwise(times)) if len(times) > 1 else 0.0
    seconds: defaultdict[tuple[str, str], float] = defaultdict(float)
    for i, (t_s, phase, rule) in enumerate(ticks):
        if t_s >= until_s:
            break
        end = times[i + 1] if i + 1 < len(times) else t_s + last
        seconds[(phase, rule)] += min(end, until_s) - t_s
    return dict(seconds)


def collect(folders: Iterable[Path]) -> dict[str, RuleTimes]:
    """Each controller's ``RuleTimes`` over the records in ``folders``."""
    by_controller: dict[str, RuleTimes] = defaultdict(RuleTimes)
    for folder in folders:
        trial = _read_json(folder / TRIAL_NAME)
        try:
            result, transitions = trial["result"], trial["transitions"]
            times = by_controller[str(trial["controller"])]
            if result["status"] == "inserted":
                first = float(trial["loop"]["first_tick_s"])
                until = first + float(result["time_to_insert_s"])
                times.inserted += 1
                times.time_to_insert_s += float(result["time_to_insert_s"])
                for key, seconds in tick_seconds(_ticks(folder / TICKS_NAME), until).items():
                    times.seconds[key] += seconds
            elif result["status"] == "failed":
                last = transitions[-1] if transitions else {"from": "?"}
                ending = (str(last["from"]), str(result["failure_reason"]))
                times.endings[ending] += 1
                if not any(t["reason"] in FOUND for t in transitions):
                    times.unfound[ending] += 1
        except (KeyError, TypeError, ValueError, IndexError) as exc:
            raise ToolError(
                f"'{folder / TRIAL_NAME}': not a trial's result (missing or bad {exc}); "
                "expected what run_trial writes"
            ) from None
    return dict(by_controller)


def _time_table(times: RuleTimes, least_s: float) -> list[str]:
    n = times.inserted
    mean_tti = times.time_to_insert_s / n
    phases: defaultdict[str, defaultdict[str, float]] = defaultdict(lambda: defaultdict(float))
    for (phase, rule), seconds in times.seconds.items():
        phases[phase][rule] += seconds / n
    lines = [
        f"{n} inserted, mean time to insert {mean_tti:.2f} s; seconds per trial, mean:",
        "",
        "| phase | rule | s per trial | share |",
        "|---|---|---|---|",
    ]
    for phase, rules in sorted(phases.items(), key=lambda item: -sum(item[1].values())):
        total = sum(rules.values())
        lines.append(f"| {phase} | (all) | {total:.2f} | {100 * total / mean_tti:.0f} % |")
        other = sum(s for s in rules.values() if s < least_s)
        for rule, seconds in sorted(rules.items(), key=lambda item: -item[1]):
            if seconds >= least_s:
                lines.append(f"| | {rule} | {seconds:.2f} | {100 * seconds / mean_tti:.0f} % |")
        if other > 0.0:
            lines.append(f"| | other | {other:.2f} | {100 * other / mean_tti:.0f} % |")
    return lines


def _failure_table(times: RuleTimes) -> list[str]:
    lines = [
        f"{sum(times.endings.values())} failed:",
        "",
        "| phase it ended in | reason | trials | of them never found the hole |",
        "|---|---|---|---|",
    ]
    for (phase, reason), count in times.endings.most_common():
        lines.append(f"| {phase} | {reason} | {count} | {times.unfound[(phase, reason)]} |")
    return lines


def report(out: Path, least_s: float) -> str:
    """The markdown report of the records in ``out`` (see the module doc)."""
    sections = []
    for controller, times in sorted(collect(record_folders(out)).items()):
        lines = [f"### `{controller}`", ""]
        if times.inserted:
            lines += _time_table(times, least_s) + [""]
        if times.endings:
            lines += _failure_table(times) + [""]
        if not times.inserted and not times.endings:
            lines += ["no finished trial (none inserted or failed)", ""]
        sections.append("\n".join(lines))
    return "\n".join(sections)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog=job_prog("where_time_goes"), description=__doc__.splitlines()[0]
    )
    parser.add_argument(
        "out", type=Path, help="a run_trials --records output folder, or a run_trial --out one"
    )
    parser.add_argument(
        "--least",
        type=number(0.0, 1e6, "s"),
        default=0.1,
        help="rules under this many seconds a trial are summed into 'other' (default 0.1)",
    )
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)

    def body() -> int:
        if not args.out.is_dir():
            raise ToolError(f"'{args.out}' is not a folder; expected a trial's or a batch's output")
        print(report(args.out, args.least), end="")
        return 0

    return run_tool("where_time_goes", body)
