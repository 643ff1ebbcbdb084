"""Run a search's simulations on a Dask cluster.

With no address, starts a local 2-worker cluster (the same API as a real one); with an address, connects to an
existing scheduler (``dask scheduler`` + ``dask worker tcp://HOST:8786``; see docs/agents.md for Kubernetes).

    python examples/dask_cluster.py                                  # LocalCluster, 2 workers
    python examples/dask_cluster.py --scheduler tcp://10.0.0.5:8786  # an existing cluster
    python examples/dask_cluster.py --budget 3 --runs 2              # CI
"""
import argparse
import warnings

import gymnasium as gym

import surrealist_gym  # noqa: F401 - registers the envs
from search import RandomSearch


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scheduler", default=None, help="tcp://host:port of a running Dask scheduler")
    parser.add_argument("--budget", type=int, default=10)
    parser.add_argument("--runs", type=int, default=4)
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    from distributed import Client, LocalCluster

    cluster = None if args.scheduler else LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=None)
    client = Client(args.scheduler or cluster)
    print(f"{len(client.scheduler_info()['workers'])} Dask workers")
    env = gym.make("Surrealist-Generate-v0", budget=args.budget, runs=args.runs, executor=client)
    result = RandomSearch(seed=0).run(env)
    print(f"best fitness {result.best_fitness:.2f} after {result.evaluations} evaluations "
          f"({env.unwrapped.evaluator.simulations} simulations on the cluster)")
    env.close()
    client.close()
    if cluster is not None:
        cluster.close()


if __name__ == "__main__":  # Dask's worker processes re-import this file
    main()
