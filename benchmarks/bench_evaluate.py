"""``surrealist evaluate`` on 30 competition tests x 5 runs: wall time against the same runs flown one by one.

    python benchmarks/bench_evaluate.py                    # 21 CAMBA + 9 rilast tests, 5 runs, 2 workers
    python benchmarks/bench_evaluate.py --limit 6 --runs 2 # a quick look
    python benchmarks/bench_evaluate.py --executor         # also the project's LocalPoolExecutor, test by test

The suite: the 21 CAMBA tests (``../shared/data/competition/camba-collection``) and 9 rilast tests (every 150th row
of ``rilast-mission1/tests.csv``) written as YAMLs to a temporary folder. The evaluation is timed end to end
(loading and checking the tests, flying, statistics, ``report.md``, CSVs and figures). Baseline, measured in the
same run: the same runs (same tests, seeds and profiles) flown one by one in this process, the way a script calling
``simulate_runs(test, [i], seed, config)`` in a loop would; the speed-up is its wall time over the evaluation's.
With ``--executor``, a second reference: each test's runs split over the workers by
:class:`~surrealist_gym.executors.LocalPoolExecutor`, one test at a time. Target: 30 tests x 5 runs in <= 2 minutes
on 2 cores.

Other processes on the machine slow both timings down; the load average before and after is printed, and CPU
seconds beside the wall times: the workers' (children's) CPU time of the evaluation and this process's for the
baseline. From the baseline's CPU time per run, the benchmark also replays evaluate's schedule (jobs to the first
free worker) and a test-at-a-time schedule on idle cores: the wall time the machine's load does not distort (a
whole test's job costs its runs' sum, which flying them in one world matches within a few percent).
"""
from __future__ import annotations

import argparse
import os
import resource
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
COMPETITION = ROOT.parent / "shared" / "data" / "competition"
CAMBA = COMPETITION / "camba-collection"
RILAST = COMPETITION / "rilast-mission1" / "tests.csv"


def write_rilast(folder: Path, count: int = 9, every: int = 150) -> Path:
    """``count`` rilast tests (every ``every``-th row) as Aerialist YAMLs in ``folder``."""
    from surrealist_gym.aerialist import save_test
    from surrealist_gym.fidelity.labels import load_labelled_set

    lset = load_labelled_set(RILAST)
    folder.mkdir(parents=True, exist_ok=True)
    for label, test in list(zip(lset.labels, lset.tests))[::every][:count]:
        save_test(test, folder / f"rilast-{label.test_id}.yaml")
    return folder


def inline(tests, runs: int, seed: int) -> tuple[float, list[list[float]]]:
    """Wall time [s] of the same runs flown one by one in this process, and each run's CPU time [s]."""
    from surrealist_gym.executors import fly_records
    from surrealist_gym.sim.profiles import default_profile

    start, costs = time.perf_counter(), []
    for _, test in tests:
        config = default_profile(test).sim_config()
        costs.append([])
        for i in range(runs):
            cpu = time.process_time()
            fly_records(test, [i], seed, config)
            costs[-1].append(time.process_time() - cpu)
    return time.perf_counter() - start, costs


def scheduled(costs: list[list[float]], workers: int) -> tuple[float, float]:
    """Wall times [s] on idle cores, from each run's CPU time: evaluate's jobs (``_jobs``), each given to the first
    free worker in submission order; and a test at a time with its runs split over the workers (LocalPoolExecutor)."""
    from surrealist_gym.executors import _chunks, _jobs

    free = [0.0] * workers
    for i, chunk in _jobs(len(costs), len(costs[0]), workers):
        free[free.index(min(free))] += sum(costs[i][k] for k in chunk)
    per_test = sum(max(sum(c[k] for k in chunk) for chunk in _chunks(range(len(c)), workers)) for c in costs)
    return max(free), per_test


def executor(tests, runs: int, seed: int, workers: int) -> float:
    """Wall time [s] of the project's LocalPoolExecutor, test after test (each test's runs split over the pool)."""
    from surrealist_gym.executors import LocalPoolExecutor
    from surrealist_gym.sim.profiles import default_profile

    pool = LocalPoolExecutor(workers)
    try:
        pool.run(tests[0][1], [0], seed, default_profile(tests[0][1]).sim_config())  # start the workers
        start = time.perf_counter()
        for _, test in tests:
            pool.run(test, range(runs), seed, default_profile(test).sim_config())
        return time.perf_counter() - start
    finally:
        pool.close()


def _children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--random-seed", type=int, default=0)
    parser.add_argument("--limit", type=int, default=None, help="the first N tests only")
    parser.add_argument("--executor", action="store_true", help="also time LocalPoolExecutor, test by test")
    parser.add_argument("--skip-baseline", action="store_true", help="time the evaluation alone")
    args = parser.parse_args()
    if not CAMBA.is_dir():
        print(f"needs the shared data folder {COMPETITION}", file=sys.stderr)
        return 1
    from surrealist_gym.cli.competition.evaluate import summary_text
    from surrealist_gym.competition.reevaluation import evaluate
    from surrealist_gym.competition.reports.evaluation import write_report
    from surrealist_gym.competition.tool_output import load_tests
    from surrealist_gym.executors import fly_records

    load = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as tmp:
        rilast = write_rilast(Path(tmp) / "rilast")
        start, children = time.perf_counter(), _children_cpu()
        tests = load_tests([CAMBA, rilast])[:args.limit]
        ev = evaluate(tests, runs=args.runs, seed=args.random_seed, workers=args.workers)
        write_report(ev, Path(tmp) / "out")
        wall, cpu = time.perf_counter() - start, _children_cpu() - children
        print(summary_text(ev))
        total = len(tests) * args.runs
        print(f"\n== {len(tests)} tests x {args.runs} runs on {args.workers} workers ({os.cpu_count()} cores; "
              f"load average {load:.1f} before)")
        print(f"surrealist evaluate: {wall:.1f} s end to end (flying {ev.wall_s:.1f} s), {total / wall:.2f} runs/s; "
              f"target <= 120 s: {'met' if wall <= 120 else 'NOT met'}; workers' CPU {cpu:.1f} s "
              f"(/ {args.workers} = {cpu / args.workers:.1f} s)")
        if not args.skip_baseline:
            fly_records(tests[0][1], [0], args.random_seed, None)  # warm-up: numba compilation, PyBullet client
            base, costs = inline(tests, args.runs, args.random_seed)
            cpu_sum = sum(map(sum, costs))
            print(f"baseline, the same runs one by one inline: {base:.1f} s (CPU {cpu_sum:.1f} s) -> speed-up "
                  f"{base / wall:.2f}x (flying alone {base / ev.wall_s:.2f}x)")
            ideal, per_test = scheduled(costs, args.workers)
            rest = wall - ev.wall_s
            print(f"on {args.workers} idle cores, from the runs' CPU times: evaluate's schedule {ideal:.1f} s flying "
                  f"(+ {rest:.1f} s loading and report = {ideal + rest:.1f} s; speed-up {cpu_sum / ideal:.2f}x over "
                  f"one by one), a test at a time split over the workers {per_test:.1f} s")
        print(f"load average after: {os.getloadavg()[0]:.1f}")
        if args.executor:
            pool = executor(tests, args.runs, args.random_seed, args.workers)
            print(f"LocalPoolExecutor, test by test: {pool:.1f} s -> evaluate is {pool / wall:.2f}x faster")
    return 0


if __name__ == "__main__":
    sys.exit(main())
