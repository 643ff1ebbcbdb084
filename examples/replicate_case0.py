"""Replicate the paper's real flight (case0.ulg, seed 1) with the adaptive greedy search.

    python examples/replicate_case0.py --budget 100 --runs 5     # the paper's RQ1 setting (minutes)
    python examples/replicate_case0.py --budget 4 --runs 1       # a quick look (CI)
"""
import argparse

import gymnasium as gym

import surrealist_gym  # noqa: F401 - registers the envs
from search import AdaptiveGreedy

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--budget", type=int, default=20)
parser.add_argument("--runs", type=int, default=1)
parser.add_argument("--inline", action="store_true", help="simulate in this process")
args = parser.parse_args()

env = gym.make("Surrealist-Replicate-v0", budget=args.budget, runs=args.runs, flyable=False,  # the paper's actions
               executor="inline" if args.inline else None)
result = AdaptiveGreedy("authors").run(env, seed=0)
seed, best = env.unwrapped.seed_evaluation, env.unwrapped.best
print(f"DTW {seed.terms['dtw']:.1f} -> {best.terms['dtw']:.1f} (Frechet {seed.terms['frechet']:.2f} m -> "
      f"{best.terms['frechet']:.2f} m) after {result.evaluations_to_best} of {result.evaluations} evaluations")
print("best obstacle:", best.test.obstacles[0])
env.close()
