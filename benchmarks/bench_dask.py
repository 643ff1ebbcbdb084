"""Evaluation throughput on a Dask LocalCluster and on threads of one process, against the local process pool with
the same number of workers.

    python benchmarks/bench_dask.py [--workers 2] [--tests 6] [--runs 4]

Every executor simulates the same tests (the case0 seed-1 box moved to ``--tests`` places, ``--runs`` runs each,
split over the workers as an evaluation does) after a warm-up evaluation (worker start-up, imports and numba
compilation excluded): the local process pool; a Dask LocalCluster of ``--workers`` processes with one thread each,
and of one process with ``--workers`` threads; ``--workers`` threads of this process. Prints simulations per second of
each and its ratio to the pool, measured in one run.
"""
from __future__ import annotations

import argparse
import time
import warnings
from dataclasses import replace


def _tests(n: int):
    import surrealist_gym as sg

    seed = sg.load_test(sg.data_path("rq1-seed1.yaml"))
    box = seed.obstacles[0]
    return [seed.with_obstacles([replace(box, x=box.x + 0.7 * i, y=box.y - 0.5 * i)]) for i in range(n)]


def throughput(executor, tests, runs: int) -> float:
    """Simulations per second of ``executor`` over ``tests`` (after one warm-up evaluation)."""
    from surrealist_gym.sim import SimConfig

    config = SimConfig()
    executor.run(tests[0], range(runs), 1, config)  # warm-up: worker start, imports, numba compilation
    start = time.perf_counter()
    for test in tests:
        executor.run(test, range(runs), 0, config)
    return len(tests) * runs / (time.perf_counter() - start)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--tests", type=int, default=6)
    parser.add_argument("--runs", type=int, default=4)
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    import distributed

    from surrealist_gym.executors import DaskExecutor, executor_for

    tests = _tests(args.tests)
    rates = {}
    with executor_for("process", args.workers) as pool:
        rates["local process pool"] = throughput(pool, tests, args.runs)
    for processes, threads in ((args.workers, 1), (1, args.workers)):
        with distributed.LocalCluster(n_workers=processes, threads_per_worker=threads, processes=True,
                                      dashboard_address=None) as cluster, distributed.Client(cluster) as client:
            rates[f"Dask LocalCluster, {processes} x {threads} thread(s)"] = throughput(DaskExecutor(client), tests,
                                                                                          args.runs)
    with executor_for("threads", args.workers) as pool:
        rates[f"{args.workers} threads of this process"] = throughput(pool, tests, args.runs)
    print(f"{args.tests} tests x {args.runs} runs on {args.workers} workers")
    base = rates["local process pool"]
    for name, rate in rates.items():
        print(f"{name + ':':42s} {rate:6.2f} simulations/s, {rate / base:.2f}x the pool")


if __name__ == "__main__":
    main()
