"""Pre-screen the greedy's mutations with a surrogate trained on a past search, and compare with greedy alone.

    python examples/prescreen_greedy.py --budget 20 --runs 10 --first-runs 3
    python examples/prescreen_greedy.py --budget 3 --runs 2 --first-runs 1 --kind knn     # CI

The model learns the RQ2 generation fitness from a stored search (by default the one shipped in
tests/data/stores/), with one low-fidelity flight of each test among its features. Between the greedy's ask and
tell (``Prescreened`` runs that loop with a ``Prescreener``), it skips candidates whose coarse flight falls clearly
short of the best test's, and races the rest: their first runs are flown, the others only if they keep up. Same as
``surrealist generate --surrogate MODEL --first-runs K``.
"""
import argparse
import time
from pathlib import Path

import gymnasium as gym

import surrealist_gym  # noqa: F401 - registers the envs
from search import AdaptiveGreedy
from surrogates.config import PrescreenConfig
from surrogates.dataset import Featurizer, load_dataset
from surrogates.models import train_model
from surrogates.prescreened import Prescreened

STORE = Path(__file__).resolve().parents[1] / "tests" / "data" / "stores" / "rq2-rep0.sqlite"

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--store", nargs="+", default=[str(STORE)], help="evaluation stores of past RQ2 searches")
parser.add_argument("--budget", type=int, default=20)
parser.add_argument("--runs", type=int, default=10)
parser.add_argument("--first-runs", type=int, default=3, help="racing: runs flown before the rest (0: off)")
parser.add_argument("--kind", default="ensemble", choices=("ensemble", "knn"))
parser.add_argument("--random-seed", type=int, default=0, help="seed of the noise, the model and the agents")
args = parser.parse_args()

featurizer = Featurizer.for_problem("generate", lowfi=True)
start = time.perf_counter()
model = train_model(load_dataset(args.store, featurizer), featurizer, args.kind, seed=args.random_seed)
print(f"model: {args.kind} on {len(model.train_y)} stored evaluations, trained in {time.perf_counter() - start:.1f} s")

agents = {"greedy": AdaptiveGreedy("paper", seed=args.random_seed),
          "greedy+prescreen": Prescreened(AdaptiveGreedy("paper"), model,
                                          PrescreenConfig.of(first_runs=args.first_runs), seed=args.random_seed)}
for name, agent in agents.items():
    env = gym.make("Surrealist-Generate-v0", budget=args.budget, runs=args.runs, executor="inline")
    steps = []  # the info of every simulated step: info["simulations"] counts the runs flown so far
    start = time.perf_counter()
    result = agent.run(env, seed=args.random_seed, callback=steps.append)
    line = (f"{name:>16}: fitness {result.history[0]:.2f} -> {result.best_fitness:.2f}, "
            f"{steps[-1]['simulations'] if steps else args.runs} simulations, {time.perf_counter() - start:.1f} s")
    if isinstance(agent, Prescreened):
        screened = agent.prescreener  # what the batch evaluator between the greedy's ask and tell did
        line += (f"; {len(screened.skipped) - screened.dropped} candidates skipped, "
                 f"{screened.dropped} dropped after their first runs")
    print(line)
    env.close()
