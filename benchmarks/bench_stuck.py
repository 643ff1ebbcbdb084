"""How early a stuck run can end with the outcome its full flight would have had (docs/compiled-loop.md).

    python benchmarks/bench_stuck.py [--windows 30,60,120] [--progress 0.5] [--workers 2] [--limit N]

Flies rilast-mission1's 1,350 tests once (seed 0, ``px4-v1.12-sitl-iris``) to the profile's 500 s limit, then again
with the stuck check on (``SimConfig.stuck_window_s``: a run ends when its distance to its goal has not shrunk by
``--progress`` m during the window) for each window, the same noise in every pass. Against the full flights, per
window: the runs it ended; of those, the ones whose full flight did not time out (the check changed their status) and
the ones whose full flight came more than 0.05 m closer than the stopped run (it changed their distance), the largest
such change and the nearest full-flight distance among them; the simulated and wall time saved, the wall time as a
ratio of the full pass measured in the same run.
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
DATA = ROOT.parent / "shared" / "data" / "competition" / "rilast-mission1" / "tests.csv"
TOLERANCE_M = 0.05  #: a stopped run keeps its full flight's distance when within this [m]


def windows(text: str) -> tuple[float, ...]:
    """``30,60,120`` -> the windows [s], each > 0."""
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected seconds separated by commas, got {text!r}") from None
    if not values or any(not math.isfinite(v) or v <= 0 for v in values):
        raise argparse.ArgumentTypeError(f"expected windows > 0 s, got {text!r}")
    return values


def fly(tests, config, workers: int) -> tuple[list, float]:
    """One run of each test; the runs and the wall time [s]."""
    from surrealist_gym.fidelity.measure import fly_tests

    start = time.perf_counter()
    outcomes = fly_tests(tests, 1, 0, config, workers)
    return [o[0] for o in outcomes], time.perf_counter() - start


def compare(full, stopped) -> dict:
    """The stopped pass against the full one, run by run."""
    ended = [(f, s) for f, s in zip(full, stopped) if s.status == "stuck"]
    finished = {f.status for f, _ in ended if f.status != "timeout"}  # what the check cut short
    timed_out = [(f, s) for f, s in ended if f.status == "timeout"]
    closer = [(f, s) for f, s in timed_out if _closer(f.distance, s.distance)]
    return {"ended": len(ended), "of_timeouts": len(timed_out), "timeouts": sum(f.status == "timeout" for f in full),
            "changed_status": len(ended) - len(timed_out), "changed_distance": len(closer),
            "largest_change_m": max((s.distance - f.distance for f, s in closer if math.isfinite(s.distance)),
                                    default=0.0),
            "closest_changed_m": min((f.distance for f, _ in closer), default=math.inf),
            "sim_saved_s": sum(f.duration - s.duration for f, s in ended),
            "sim_full_s": sum(f.duration for f in full),
            "changed": sorted(finished)}


def _closer(full: float, stopped: float) -> bool:
    """Whether the full flight came more than TOLERANCE_M closer than the stopped run did."""
    if not math.isfinite(full):
        return False
    return not math.isfinite(stopped) or stopped - full > TOLERANCE_M


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--windows", type=windows, default=(30.0, 60.0, 120.0), help="stuck windows [s]")
    parser.add_argument("--progress", type=float, default=0.5, help="progress toward the goal that resets the "
                                                                    "window [m] (default 0.5)")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--limit", type=int, default=None, help="the first N tests only")
    args = parser.parse_args(argv)

    from surrealist_gym.fidelity.labels import load_labelled_set
    from surrealist_gym.sim.uav import decide_uav

    tests = list(load_labelled_set(DATA).tests)[:args.limit]
    config = decide_uav(uav="px4-v1.12-sitl-iris").config
    full, full_s = fly(tests, config, args.workers)
    print(f"{len(tests)} rilast-mission1 tests, 1 run each (seed 0), px4-v1.12-sitl-iris, {args.workers} workers")
    print(f"full flights to the {config.timeout_s:g} s limit: {full_s:.1f} s wall, "
          f"{sum(f.status == 'timeout' for f in full)} time-outs holding "
          f"{sum(f.duration for f in full if f.status == 'timeout') / max(1e-9, sum(f.duration for f in full)):.0%} "
          f"of the simulated time")
    print(f"\n{'window':>8} {'ended':>6} {'of time-outs':>13} {'status changed':>15} {'distance changed':>17} "
          f"{'largest':>8} {'nearest':>8} {'sim time saved':>15} {'wall':>9} {'wall / full':>12}")
    for window in args.windows:
        stopped, wall = fly(tests, replace(config, stuck_window_s=window, stuck_distance_m=args.progress),
                            args.workers)
        c = compare(full, stopped)
        print(f"{window:>7g}s {c['ended']:>6} {c['of_timeouts']:>6} of {c['timeouts']:<5} {c['changed_status']:>15} "
              f"{c['changed_distance']:>17} {c['largest_change_m']:>7.2f}m {c['closest_changed_m']:>7.2f}m "
              f"{c['sim_saved_s'] / c['sim_full_s']:>15.0%} {wall:>8.1f}s "
              f"{wall / full_s:>12.2f}" + (f"   changed: {', '.join(c['changed'])}" if c["changed"] else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
