"""The 2024 similarity threshold (``competition.scoring.SIMILAR_FLIGHT_M``): how far apart the averaged flights of one
test and of two different tests are.

    python benchmarks/bench_similarity.py --out results/similarity     # CAMBA's 21 tests x 10 runs, 2 workers
    python benchmarks/bench_similarity.py --out results/similarity     # again: reads the runs back, flies none

Each CAMBA test (``../shared/data/competition/camba-collection``) is flown 10 times
(``competition.reevaluation.evaluate``, stored in ``--out``, so a second call or an interrupted one flies only what is
missing). The 2024 edition averaged each test's 5 runs and compared the averages of two tests by DTW; here the average
is DBA (``fitness.average_runs``) and the distance the mean x-y distance along DTW's path
(``competition.suite.trajectory_distance``), and the summed DTW (``metrics.dtw``, 3-D, what Aerialist's
``Trajectory.distance`` computes) beside it:

- same test: the average of runs 0-4 against the average of runs 5-9 (two evaluations of one test);
- different tests: the averages of runs 0-4 of two tests on the same mission.

A threshold below which two tests count as similar should catch most pairs of the first kind and none of the second.
"""
from __future__ import annotations

import argparse
import itertools
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
CAMBA = ROOT.parent / "shared" / "data" / "competition" / "camba-collection"


def main() -> None:
    from surrealist_gym.competition.reevaluation import evaluate
    from surrealist_gym.competition.scoring import SIMILAR_FLIGHT_M, case_study_of
    from surrealist_gym.competition.suite import trajectory_distance
    from surrealist_gym.competition.tool_output import load_tests
    from surrealist_gym.fitness import average_runs
    from surrealist_gym.metrics import dtw

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("results/similarity"), help="folder of the runs' store")
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    tests = load_tests([CAMBA])
    ev = evaluate(tests, runs=10, seed=0, workers=args.workers, store=args.out / "evaluations.sqlite",
                  progress=lambda done, total: print(f"\r{done}/{total} runs", end="", file=sys.stderr))
    print(file=sys.stderr)
    flights = {t.name: [r.trajectory for r in t.runs if r.flown and len(r.trajectory)] for t in ev.tests}
    mission = {t.name: case_study_of(t.test) for t in ev.tests}
    first = {name: average_runs(runs[:5]) for name, runs in flights.items()}
    second = {name: average_runs(runs[5:10]) for name, runs in flights.items()}
    same = {name: (trajectory_distance(first[name], second[name]), dtw(first[name], second[name])) for name in first}
    other = {(a, b): (trajectory_distance(first[a], first[b]), dtw(first[a], first[b]))
             for a, b in itertools.combinations(first, 2) if mission[a] == mission[b]}

    def show(values, digits) -> str:
        return ", ".join(f"{v:.{digits}f}" for v in sorted(values))

    print(f"{len(same)} tests x 10 runs (missions: {', '.join(sorted(set(mission.values())))}); averages of 5 runs")
    print(f"same test, mean x-y distance along DTW's path [m]: {show((m for m, _ in same.values()), 2)}")
    print(f"different tests, the 10 smallest [m]: {show(sorted(m for m, _ in other.values())[:10], 2)} "
          f"(of {len(other)} pairs; median {np.median([m for m, _ in other.values()]):.2f})")
    print(f"same test, summed DTW [m]: {show((d for _, d in same.values()), 0)}")
    print(f"different tests, summed DTW, the 10 smallest [m]: {show(sorted(d for _, d in other.values())[:10], 0)}")
    below_same = sum(m < SIMILAR_FLIGHT_M for m, _ in same.values())
    below_other = sum(m < SIMILAR_FLIGHT_M for m, _ in other.values())
    print(f"below SIMILAR_FLIGHT_M = {SIMILAR_FLIGHT_M:g} m: {below_same} of {len(same)} same-test pairs, "
          f"{below_other} of {len(other)} pairs of different tests")


if __name__ == "__main__":
    main()
