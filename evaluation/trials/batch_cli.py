"""A batch of simulated insertion trials on consecutive seeds, locally or on Ray.

    tactile trials --task usb_c --seeds 0:200 --out out/trials/usb_c
        [--controller dipole|fingervision|zero_torque|torque_only|align|blind|oracle] [--workers N]
        [--executor local|ray] [--ray-address ADDR] [--set KEY=VALUE ...] [--records] [--episodes]
        [--resume]

Seeds run from A up to B, B excluded. ``--set`` overrides a task or scene configuration key
by dotted path (``--set scene.friction=0.5``), validated like the YAML. ``--workers`` is the
number of trials run at once (1: in this process); with ``--executor ray`` the trials are
Ray tasks on a local Ray instance of that many CPUs, or on the cluster at ``--ray-address``
(then its CPUs set the parallelism). ``--records`` lets each trial write its own record and
chart (``summary.png``) under OUT/records/<controller>-<seed>/, kept there once its row is in
trials.csv (``evaluation.trials.records``); ``--episodes`` adds each trial's episode
(``episode.mcap``, docs/EPISODES.md) to its record.

OUT must be a new or empty folder. OUT/trials.csv gets one row per trial as it finishes;
OUT/summary.json (keys: docs/EVALUATION.md, ``evaluation.trials.summary``) is written at the
end. Ctrl-C or SIGTERM (to this process or its group) stops the batch within a second: the
workers are killed, the unfinished trials' records removed, and summary.json holds only the
finished trials and ``"complete": false`` (exit 130 or 143); a second signal is ignored. The
workers die with this process even if it is killed with SIGKILL. ``--resume`` continues a
batch in OUT that stopped before its end, however it stopped, when run with the same
arguments (OUT/batch.json records them; checked): its finished trials are kept and only the
others run (evaluation/trials/batch.py). A trial that raises is a
failed trial of status ``error`` (``error: ...``), not the end of the batch. Bad arguments,
an unknown task or override key, a non-empty OUT: one line ``run_trials: error: ...`` and
exit code 2.

The trial function: ``TRIAL_FUNCTION`` below names it (``module:function``, see
``evaluation.trials.spec`` for its contract and the optional ``check_spec``); the hidden
option ``--trial-function`` replaces it (tests use a fake one).
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from controller.cli.support import (
    EXIT_SIGINT,
    EXIT_SIGTERM,
    ToolError,
    add_override_argument,
    integer,
    one_line,
    run_tool,
)
from core.subcommands import job_prog
from evaluation.trials.batch import (
    SUMMARY_NAME,
    Batch,
    check_batch_folder,
    check_resume_folder,
    run_batches,
)
from evaluation.trials.executors import EXECUTORS, Executor, open_executor
from evaluation.trials.oracle import TRIAL_CONTROLLERS
from evaluation.trials.records import RECORDS
from evaluation.trials.spec import (
    SeedSpecs,
    SpecError,
    TrialFunction,
    TrialSpec,
    format_seeds,
    parse_seeds,
)

# The real trial (scene + controller). The integrator plugs it in here, and only here.
TRIAL_FUNCTION = "evaluation.trials.trial:run_trial"
MAX_WORKERS = 1024
EXIT_CODES = {"SIGINT": EXIT_SIGINT, "SIGTERM": EXIT_SIGTERM}

SpecCheck = Callable[[TrialSpec], None]


def seeds_type(text: str) -> range:
    """argparse type: seeds A:B (B excluded), checked as they are parsed."""
    try:
        return parse_seeds(text)
    except SpecError as exc:
        raise argparse.ArgumentTypeError(str(exc).removeprefix("seeds ")) from None


def add_run_arguments(parser: argparse.ArgumentParser) -> None:
    """The arguments every batch tool shares: task, seeds, executor, overrides."""
    parser.add_argument("--task", required=True, help="task configuration name or YAML path")
    parser.add_argument(
        "--seeds", type=seeds_type, required=True, help="A:B, the seeds A up to B (B excluded)"
    )
    parser.add_argument(
        "--workers",
        type=integer(1, MAX_WORKERS),
        default=1,
        help="trials run at once (default 1: in this process)",
    )
    parser.add_argument("--executor", choices=EXECUTORS, default="local")
    parser.add_argument(
        "--ray-address",
        default=None,
        help="Ray cluster to join (with --executor ray; default: start a local instance)",
    )
    add_override_argument(
        parser, "override a task/scene configuration key by dotted path (repeatable)"
    )
    parser.add_argument("--out", type=Path, required=True, help="output folder")
    parser.add_argument(
        "--resume",
        action="store_true",
        help="continue the run in --out that stopped before its end: the same arguments "
        "(checked), its finished trials kept, the others run",
    )
    parser.add_argument("--trial-function", default=TRIAL_FUNCTION, help=argparse.SUPPRESS)


def check_run_arguments(parser: argparse.ArgumentParser, args: argparse.Namespace) -> None:
    """Cross-argument rules (argparse exits 2 with one error line)."""
    if args.ray_address is not None and args.executor != "ray":
        parser.error("argument --ray-address: only with --executor ray")


def load_trial_function(path: str) -> tuple[TrialFunction, SpecCheck | None]:
    """The trial function named ``module:function`` and its module's ``check_spec`` (None
    when the module has none); ToolError when it cannot be imported."""
    module_name, sep, name = path.partition(":")
    if not sep or not module_name or not name:
        raise ToolError(f"--trial-function {path!r}: expected module:function")
    try:
        module = importlib.import_module(module_name)
    except ImportError as exc:
        raise ToolError(f"the trial function {path} cannot be imported ({one_line(exc)})") from None
    function = getattr(module, name, None)
    if not callable(function):
        raise ToolError(f"the trial function {path}: {module_name} has no function {name!r}")
    check = getattr(module, "check_spec", None)
    return function, check if callable(check) else None


def check_batches(check: SpecCheck | None, batches: Sequence[Batch]) -> None:
    """Run ``check`` before any trial on the first trial of each batch (a batch's trials
    differ only by seed: ``SeedSpecs``)."""
    if check is not None:
        for batch in batches:
            check(batch.specs[0])


def make_executor(args: argparse.Namespace) -> Executor:
    return open_executor(args.executor, args.workers, args.ray_address)


def executor_context(args: argparse.Namespace) -> dict[str, Any]:
    """What the summary records about how the trials ran."""
    context: dict[str, Any] = {"executor": args.executor, "workers": args.workers}
    if args.ray_address is not None:
        context["ray_address"] = args.ray_address
    return context


def describe(summary: dict[str, Any]) -> str:
    """One line of a batch summary for the terminal."""
    n = summary["n"]
    if not n:
        return "no trial finished"
    low, high = summary["success_ci95"]
    parts = [
        f"{summary['successes']}/{n} succeeded ({summary['success_rate']:.1%}, "
        f"95% CI {low:.1%}-{high:.1%})"
    ]
    if summary["median_time_s"] is not None:
        parts.append(f"median {summary['median_time_s']:.2f} s, p90 {summary['p90_time_s']:.2f} s")
    parts.append(
        f"plug insertion force max {summary['max_insertion_force_n']:.2f} N "
        f"({summary['insertion_force_violation_trials']} trials over the limit), summed contact "
        f"force max {summary['max_contact_force_n']:.2f} N, max wrist "
        f"force {summary['max_wrist_force_n']:.2f} N ({summary['over_force_trials']} over)"
    )
    if summary["sim_speed_x_realtime"] is not None:
        parts.append(f"{summary['sim_speed_x_realtime']:.1f}x real time")
    return ", ".join(parts)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog=job_prog("run_trials"), description="Run a batch of simulated insertion trials."
    )
    add_run_arguments(parser)
    parser.add_argument("--controller", choices=list(TRIAL_CONTROLLERS), default="dipole")
    parser.add_argument(
        "--records",
        action="store_true",
        help="each trial writes its record and chart under OUT/records/<controller>-<seed>/",
    )
    parser.add_argument(
        "--episodes",
        action="store_true",
        help="each trial also writes its episode.mcap into its record (implies --records)",
    )
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    check_run_arguments(parser, args)
    return run_tool("run_trials", lambda: _run(args))


def check_out(args: argparse.Namespace) -> None:
    """--out: a new or empty folder, or with --resume an earlier run's folder."""
    if args.resume:
        check_resume_folder(args.out)
    else:
        check_batch_folder(args.out)


def _run(args: argparse.Namespace) -> int:
    check_out(args)
    function, check = load_trial_function(args.trial_function)
    records = args.out / RECORDS if args.records or args.episodes else None
    specs = SeedSpecs(
        args.task, args.controller, args.seeds, tuple(args.overrides), records, args.episodes
    )
    context = {
        "task": args.task,
        "controller": args.controller,
        "seeds": format_seeds(args.seeds),
        "overrides": list(args.overrides),
        "records": records is not None,
        "episodes": args.episodes,
        **executor_context(args),
    }
    batch = Batch(specs, args.out, context)
    check_batches(check, [batch])
    stopped = run_batches(function, [batch], make_executor(args), resume=args.resume)
    line = describe(batch.summary)
    if stopped is not None:
        print(
            f"run_trials: interrupted by {stopped} after {batch.summary['n']} of {len(specs)} "
            f"trials; {line}; wrote {args.out / SUMMARY_NAME}",
            file=sys.stderr,
        )
        return EXIT_CODES[stopped]
    print(f"run_trials: {args.task} {args.controller}: {line}; wrote {args.out / SUMMARY_NAME}")
    return 0
