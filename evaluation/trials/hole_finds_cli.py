"""``python -m evaluation hole_finds``: where the tip really was at each hole find, and how
the press that followed ended (evaluation/trials/hole_finds.py), over simulated trials of the
``align`` controller (the find-align-insert machine, whose SEARCH declares hole finds).

    hole_finds.py --task usb_c|usb_a|PATH.yaml --seeds A:B [--workers N] [--set KEY=VALUE ...]

Prints one line per hole find (seed, time, the rule that fired it, the true tip centre in
the opening's frame in mm, in the opening or on the surface, the pivot error at the find and
when ALIGN ended, the attempt's end) and the counts, by place and end and by rule. Writes
nothing; Ctrl-C stops the trials at once.
Bad arguments, an unknown task or key: one line and exit code 2.
"""

from __future__ import annotations

import argparse
from functools import partial

from controller.cli.support import add_override_argument, integer, run_tool
from controller.run.task import load_task
from core.subcommands import job_prog
from evaluation.common.machine_info import one_thread_env
from evaluation.common.worker_processes import kill_pool, ordered_map, worker_pool
from evaluation.trials.batch_cli import MAX_WORKERS, seeds_type
from evaluation.trials.hole_finds import HoleFind, summary_lines, trial_hole_finds


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog=job_prog("hole_finds"), description=__doc__.splitlines()[0]
    )
    parser.add_argument("--task", required=True, help="usb_c, usb_a or a task YAML path")
    parser.add_argument("--seeds", type=seeds_type, required=True, help="A:B (B excluded)")
    parser.add_argument("--workers", type=integer(1, MAX_WORKERS), default=1)
    add_override_argument(parser, "override a task key by dotted path (repeatable)")
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    return run_tool("hole_finds", lambda: _run(args))


def _one(task_name: str, overrides: tuple[str, ...], seed: int):
    return trial_hole_finds(load_task(task_name, overrides), seed)


def _run(args: argparse.Namespace) -> int:
    load_task(args.task, args.overrides)  # a bad task or key: one line, before any trial
    job = partial(_one, args.task, tuple(args.overrides))
    if args.workers == 1:
        _report(map(job, args.seeds), len(args.seeds))
        return 0
    one_thread_env()
    pool = worker_pool(args.workers)
    try:
        _report(ordered_map(pool, job, args.seeds, 2 * args.workers), len(args.seeds))
    except BaseException:  # Ctrl-C, SIGTERM, a failed trial: stop the queued trials now
        kill_pool(pool)
        raise
    pool.shutdown()
    return 0


def _report(results, trials: int) -> None:
    finds: list[HoleFind] = []
    successes = 0
    print(
        "seed  t (s)  rule          tip u / v / z (mm)       where           pivot error (mm)"
        "  attempt ended"
    )
    for success, trial in results:
        successes += success
        for f in trial:
            u, v, z = (1e3 * x for x in f.tip_o_m)
            where = "in the opening" if f.in_opening else "on the surface"
            found, aligned = (1e3 * e for e in f.pivot_error_m)
            print(
                f"{f.seed:4d} {f.t_s:6.2f}  {f.rule:12s} {u:6.2f} {v:6.2f} {z:6.2f}   {where}  "
                f"{found:5.2f} / {aligned:5.2f}     {f.outcome}"
            )
        finds.extend(trial)
    print(f"trials inserted: {successes} / {trials}; hole finds: {len(finds)}")
    for line in summary_lines(finds):
        print(line)
