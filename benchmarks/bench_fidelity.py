"""The fidelity harness on the real labelled sets: its figures, wall time and tests per second.

    python benchmarks/bench_fidelity.py                      # full rilast-mission1 (1,350 tests) and CAMBA (21)
    python benchmarks/bench_fidelity.py --workers 2 --every 10   # a tenth of rilast, on 2 processes
    python benchmarks/bench_fidelity.py --skip-rilast        # CAMBA only

Baseline, measured in the same run: a plain sequential loop (load, ``simulate(test, runs=1)``, competition
distance) over the first ``--baseline`` rilast tests in this process. The harness's speed-up is its tests/s over
the loop's. Target: the 1,350 rilast tests in <= 10 minutes on 2 cores. CAMBA uses
``benchmarks/data/camba-px4-flights.csv`` (PX4 airborne times read off the plots) when it exists, else the
folder's ``labels.csv`` (distances only).
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
COMPETITION = ROOT.parent / "shared" / "data" / "competition"
RILAST = COMPETITION / "rilast-mission1" / "tests.csv"
CAMBA = COMPETITION / "camba-collection"
CAMBA_FLIGHTS = ROOT / "benchmarks" / "data" / "camba-px4-flights.csv"


def sequential(lset, n: int) -> float:
    """Tests per second of a plain loop: simulate one run and measure the competition distance, test by test."""
    from surrealist_gym.sim import simulate
    from surrealist_gym.sim.uav import DEFAULT_UAV, decide_uav

    tests = lset.tests[:n]
    config = decide_uav(uav=DEFAULT_UAV).config  # the harness's default UAV profile
    simulate(tests[0], runs=1, seed=0, config=config)  # warm-up: numba compilation, PyBullet client
    start = time.perf_counter()
    for test in tests:
        simulate(test, runs=1, seed=0, config=config)  # each run's competition distance is computed with it
    return len(tests) / (time.perf_counter() - start)


def harness(name: str, path, labels, workers: int, limit, every: int, baseline: float | None) -> float:
    from surrealist_gym.cli.fidelity import summary_text
    from surrealist_gym.fidelity.measure import measure_fidelity

    report = measure_fidelity(path, labels=labels, workers=workers, limit=limit, every=every)
    print(f"== {name} ({workers} workers)")
    print(summary_text(report))
    rate = len(report.rows) / report.wall_s
    line = f"wall {report.wall_s:.1f} s, {rate:.2f} tests/s"
    if baseline:
        line += f"; sequential loop {baseline:.2f} tests/s -> speed-up {rate / baseline:.2f}x on {workers} workers"
    print(line)
    return rate


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1, help="processes (default: all cores)")
    parser.add_argument("--limit", type=int, default=None, help="fly at most N rilast tests")
    parser.add_argument("--every", type=int, default=1, help="fly every K-th rilast test")
    parser.add_argument("--baseline", type=int, default=10, help="tests in the sequential baseline (default 10)")
    parser.add_argument("--skip-rilast", action="store_true", help="CAMBA only")
    args = parser.parse_args()

    from surrealist_gym.fidelity.measure import load_labelled_set

    rilast = load_labelled_set(RILAST)
    baseline = sequential(rilast, args.baseline)
    print(f"sequential baseline: {baseline:.2f} tests/s over {args.baseline} rilast tests, 1 run each")
    if not args.skip_rilast:
        rate = harness("rilast-mission1", rilast, None, args.workers, args.limit, args.every, baseline)
        print(f"projected for all 1,350 rilast tests on {args.workers} workers: {1350 / rate / 60:.1f} min "
              f"(target <= 10 min on 2 cores)")
    labels = CAMBA_FLIGHTS if CAMBA_FLIGHTS.is_file() else None
    harness(f"CAMBA ({'PX4 flight durations' if labels else 'labels.csv'})", CAMBA, labels, args.workers, None, 1,
            baseline)
    return 0


if __name__ == "__main__":
    sys.exit(main())
