"""The PX4-Avoidance look-ahead tree on long flights with large clouds (docs/compiled-loop.md, section 3).

    python benchmarks/bench_tree_clouds.py                      # rilast random_run0_4, random_run0_6 (500 s
                                                                # time-outs) and random_run3_194 (2 boxes)
    python benchmarks/bench_tree_clouds.py random_run0_7 --repeat 5

For each mission1 + rilast test (run 0, seed 0, px4-v1.12-sitl-iris): the flight on the compiled loop (status,
simulated time, thread CPU time); every tree build of the same flight recorded on the Python outer loop (the
compiled loop's bit-identical reference, whose planner class calls ``px4_avoidance.build_tree``): builds per
simulated second, cloud sizes, and ``build_tree`` replayed on every build (thread CPU time per build, the least of
``--repeat`` replays, by cloud size), with the replayed total against the flight's CPU time.
"""
from __future__ import annotations

import argparse
import time

import numpy as np
from bench_compiled import _tree_calls
from bench_sim import rilast_tests

SIZES = (0, 200, 500, 800, 1100, 1400, 2000)


def clouds(test_id: str, repeat: int) -> None:
    from surrealist_gym.sim import simulate
    from surrealist_gym.sim.avoidance.px4.settings import MAX_NODES
    from surrealist_gym.sim.avoidance.px4.tree import build_tree, tree_work
    from surrealist_gym.sim.profiles import load_profile

    cfg = load_profile("px4-v1.12-sitl-iris").sim_config()
    (test,) = rilast_tests([test_id])
    simulate(test, runs=1, config=cfg)  # warm-up
    t0 = time.thread_time()
    (run,) = simulate(test, runs=1, config=cfg)
    flight = time.thread_time() - t0
    calls = _tree_calls(test, cfg)
    sizes = np.array([c[0].shape[0] for c in calls])
    path, work = np.empty((MAX_NODES, 3)), tree_work(calls[0][5])
    per = np.full(len(calls), np.inf)
    for _ in range(repeat):
        for j, args in enumerate(calls):
            t0 = time.thread_time_ns()
            build_tree(*args, path, work)
            per[j] = min(per[j], time.thread_time_ns() - t0)
    per *= 1e-9
    print(f"{test_id}: {run.status.value} after {run.duration:.1f} s, flight {flight:.2f} s CPU "
          f"({run.duration / flight:.0f}x); {len(calls)} builds ({len(calls) / run.duration:.1f} per simulated s), "
          f"cloud mean {sizes.mean():.0f}, max {sizes.max()} points; replayed builds {per.sum():.2f} s "
          f"({per.sum() / flight:.0%} of the flight), {per.mean() * 1e6:.0f} us per build")
    for lo, hi in zip(SIZES, SIZES[1:]):
        m = (sizes >= lo) & (sizes < hi)
        if m.any():
            print(f"  clouds of {lo}-{hi} points: {m.sum()} builds, median {np.median(per[m]) * 1e6:.0f} us per build")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("tests", nargs="*", default=["random_run0_4", "random_run0_6", "random_run3_194"])
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    for test_id in args.tests:
        clouds(test_id, args.repeat)


if __name__ == "__main__":
    main()
