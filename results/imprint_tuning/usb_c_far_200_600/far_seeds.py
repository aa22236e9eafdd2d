"""Run `dipole` on the seeds of A:B whose opening lies more than 2.5 mm off the nominal in x or
y (the scene's draws), two at a time, and write their results as one CSV.

    PYTHONPATH=CHECKOUT python far_seeds.py TASK A B OUT.csv [KEY=VALUE ...]
"""

import csv
import dataclasses
import sys
from multiprocessing import Pool

from controller.run.task import load_task
from drivers.sim.scenes.insertion.draws import draw_scene
from evaluation.trials.spec import TrialSpec
from evaluation.trials.trial import run_trial

FAR_M = 0.0025


def far_seeds(task: str, first: int, end: int) -> list[int]:
    config = load_task(task)
    seeds = []
    for seed in range(first, end):
        hole = draw_scene(config.config.hole, config.scene, seed).hole
        nominal = config.config.hole
        if abs(hole.x_m - nominal.x_m) > FAR_M or abs(hole.y_m - nominal.y_m) > FAR_M:
            seeds.append(seed)
    return seeds


def main() -> None:
    task, first, end, out = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
    overrides = tuple(sys.argv[5:])
    seeds = far_seeds(task, first, end)
    with Pool(2) as pool:
        rows = pool.starmap(_one, [(task, seed, overrides) for seed in seeds], chunksize=1)
    with open(out, "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    print(f"{sum(r['success'] for r in rows)}/{len(rows)} inserted")


def _one(task: str, seed: int, overrides: tuple[str, ...]) -> dict:
    return dataclasses.asdict(run_trial(TrialSpec(task, "dipole", seed, overrides)))


if __name__ == "__main__":
    main()
