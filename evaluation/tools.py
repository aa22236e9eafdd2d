"""The research, figure and benchmark tools, apart from the product's command: ``python -m
evaluation TOOL [ARGS ...]`` (``python -m evaluation --help`` lists them; ``TOOL --help``
gives a tool's options). Each tool is its module's ``main``, imported only when chosen
(core/subcommands.py), through ``core.entry_point.run_main``."""

from __future__ import annotations

from collections.abc import Sequence

from core.subcommands import Group, Job, dispatch

ONE_THREAD = "evaluation.common.machine_info:one_thread_env"
"""Called before a speed benchmark's modules load: the numerical libraries on one thread."""

DESCRIPTION = "The research, figure and benchmark tools (the product's jobs: tactile --help)."

GROUPS = (
    Group(
        "benchmarks (docs/BENCHMARKS.md)",
        (
            Job("bench_camera_decode", "evaluation.bench.camera_decode",
                "Mini frame decoding, full vs reduced"),
            Job("bench_episode", "evaluation.bench.episode",
                "the episode writer's crash loss, cost and size"),
            Job("bench_episode_stages", "evaluation.bench.episode_stages",
                "the episode writer thread's CPU by stage and topic"),
            Job("bench_estimation", "evaluation.bench.estimation",
                "speed and field error of each estimator configuration"),
            Job("bench_gel", "evaluation.bench.gel", "speed of the gel model, on one thread",
                ONE_THREAD),
            Job("bench_insertion_scene", "evaluation.bench.insertion_scene",
                "speed of the simulated insertion scene, on one thread", ONE_THREAD),
            Job("bench_loop", "evaluation.bench.loop_period",
                "period accuracy of the real-time control loop"),
            Job("bench_render", "evaluation.bench.render",
                "speed of the simulated camera's renderer, on one thread", ONE_THREAD),
            Job("bench_slip", "evaluation.bench.slip_detection",
                "per-frame cost of the slip detector and of the estimator's push"),
            Job("bench_teleop", "evaluation.bench.teleop_demo",
                "the teleop demo's view cost and unplug stop latency"),
            Job("trial_fingerprints", "evaluation.bench.trial_fingerprints",
                "digests of what simulated trials decided, per seed", ONE_THREAD),
        ),
    ),
    Group(
        "insertion trials in simulation",
        (
            Job("calibrate_task", "evaluation.offline.calibrate_task_cli",
                "fit a task's calibration in its simulated scene"),
            Job("draw_failures", "evaluation.trials.draw_failures",
                "which per-seed scene draws a batch's failures share"),
            Job("fit_axial_map", "evaluation.trials.axial_map_cli",
                "the touch spiral's axial-force map"),
            Job("fit_imprint_gain", "evaluation.trials.imprint_gain_cli",
                "the touch spiral's imprint gain (the plug's offset across the fingers)"),
            Job("grasp_scores", "evaluation.trials.grasp_scores_cli",
                "FEEL's in-hand estimate against the truth, from batch folders"),
            Job("hole_finds", "evaluation.trials.hole_finds_cli",
                "where the tip really was at each hole find"),
            Job("near_miss_sides", "evaluation.trials.near_miss_sides",
                "whether the sweep's near misses name the opening's side"),
            Job("publish_trials", "evaluation.trials.publish",
                "publish make trials' comparisons into docs/"),
            Job("search_torques", "evaluation.scene.search_torques",
                "the true gel torques during the search against the wrist's stiffness"),
            Job("sensor_levels", "evaluation.scene.sensor_levels",
                "the insertion scene's camera effects against the real captures"),
            Job("success_chart", "evaluation.trials.success_chart_cli",
                "success against time to insert, charted from batch folders"),
            Job("where_time_goes", "evaluation.trials.where_time_goes",
                "where trials spend their time, rule by rule"),
        ),
    ),
    Group(
        "estimator experiments (docs/EVALUATION.md)",
        (
            Job("demo", "evaluation.offline.estimator_demo",
                "the offline estimator demo on a synthetic sequence"),
            Job("eval_press_roll", "evaluation.experiments.press_roll_eval",
                "tilt estimates on a simulated ball pressed and rolled"),
            Job("eval_slip", "evaluation.experiments.slip_cli",
                "score the estimator's slip flags on the simulated gel"),
            Job("evaluate", "evaluation.experiments.run",
                "regenerate docs/EVALUATION.md and its charts"),
            Job("make_dataset", "evaluation.offline.make_dataset_cli",
                "write a simulated calibration dataset"),
        ),
    ),
    Group(
        "real gels and the renderer's look",
        (
            Job("appearance_figure", "evaluation.appearance.figure",
                "real gel captures beside rendered frames, and their statistics"),
            Job("check_real_recordings", "evaluation.real_recordings.recordings_cli",
                "estimators on rendered real-texture recordings"),
            Job("fit_appearance", "evaluation.appearance.fit",
                "fit the renderer's realistic looks to the shipped real captures"),
            Job("gel_stats", "evaluation.appearance.stats_cli",
                "appearance statistics of gel images, image folders or videos"),
            Job("realgel_check", "evaluation.realgel.check_cli",
                "estimators on real gel textures under an independent elastic model"),
            Job("realgel_origins", "evaluation.realgel.origins_cli",
                "the dipole's origin under pushing, on the true field"),
        ),
    ),
    Group(
        "episodes and the teleop demo",
        (
            Job("check_lerobot", "evaluation.episodes.lerobot_check",
                "load a LeRobot export with the real lerobot and check every frame"),
            Job("teleop_screenshot", "evaluation.teleop.screenshot",
                "the live view's picture at a moment of an episode"),
            Job("teleop_sign_figure", "evaluation.teleop.sign_figure",
                "the alignment demo's sign drawing"),
        ),
    ),
)  # fmt: skip
"""The tools, by what they measure or make."""


def main(argv: Sequence[str] | None = None) -> int | None:
    """Run the tool ``argv`` names (default ``sys.argv[1:]``); its exit code."""
    return dispatch("python -m evaluation", DESCRIPTION, GROUPS, argv)
