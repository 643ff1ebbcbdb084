"""The paper's noise floor (section 4.1, "minimum feasible distance"), measured in our simulator.

    python benchmarks/bench_noise_floor.py [--seed rq1-seed1] [--uav px4-vision-sitl] [--repetitions 10]
                                           [--runs 5] [--workers 1]

As the paper measured it: the seed test of RQ1 is evaluated once per repetition (repetition ``r`` flies its ``runs``
runs with base seed ``r``, as ``benchmarks/reproduce_paper.py`` does), each evaluation's runs are averaged (DBA, the
replication fitness's average), and the DTW between every pair of the averaged trajectories is reported (min, max,
mean). The paper's Gazebo figures: 15.9-121.3, mean 58.5. ``--uav`` defaults to the log's own vehicle (the RQ1
set-up); ``--json`` prints the figures as JSON.
"""
from __future__ import annotations

import argparse
import itertools
import json

import numpy as np

import surrealist_gym as sg
from surrealist_gym.envs.replicate import ReplicateEnv
from surrealist_gym.metrics import dtw

PAPER = (15.9, 121.3, 58.5)


def averaged_seed_flights(seed: str, uav, repetitions: int, runs: int, workers: int) -> list[np.ndarray]:
    """The averaged trajectory of the seed test's ``runs`` runs, one per repetition (base seed = repetition)."""
    out = []
    for rep in range(repetitions):
        env = ReplicateEnv(seed_test=sg.data_path(f"{seed}.yaml"), runs=runs, random_seed=rep, uav=uav,
                           workers=workers)
        evaluation = env.evaluator.evaluate(env.seed_test)
        out.append(np.asarray(evaluation.trajectory))
    return out


def noise_floor(averages: list[np.ndarray]) -> dict:
    """Min, max and mean of the pairwise DTW between the averaged trajectories."""
    d = [dtw(a, b) for a, b in itertools.combinations(averages, 2)]
    return {"pairs": len(d), "min": float(min(d)), "max": float(max(d)), "mean": float(np.mean(d))}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seed", default="rq1-seed1", choices=["rq1-seed1", "rq1-seed2"])
    parser.add_argument("--uav", default=None, help="UAV profile (default: the log's vehicle, px4-vision-case0)")
    parser.add_argument("--repetitions", type=int, default=10)
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    floor = noise_floor(averaged_seed_flights(args.seed, args.uav, args.repetitions, args.runs, args.workers))
    floor.update(seed=args.seed, uav=args.uav or "log's vehicle", repetitions=args.repetitions, runs=args.runs)
    if args.json:
        print(json.dumps(floor))
        return
    print(f"{args.seed}, UAV {floor['uav']}: pairwise DTW of {args.repetitions} averaged seed flights "
          f"({args.runs} runs each): {floor['min']:.1f}-{floor['max']:.1f}, mean {floor['mean']:.1f} "
          f"(paper, Gazebo: {PAPER[0]}-{PAPER[1]}, mean {PAPER[2]})")


if __name__ == "__main__":
    main()
