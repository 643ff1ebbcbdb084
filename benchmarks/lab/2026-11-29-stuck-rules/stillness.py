"""Could a hovering run end early on stillness? Offline, on rilast-mission1's full flights.

    python benchmarks/lab/2026-11-29-stuck-rules/stillness.py [--cache results/stuck-full.pkl]

Flies the 1,350 tests once (seed 0, px4-v1.12-sitl-iris, to the 500 s limit; kept in ``--cache``), then for each
rule finds the first moment it would end each run: airborne (above 1 m) and within R m of its mean position for
the last W s ("still"), and also with its closest approach to a box unchanged (by 0.01 m) over those W s
("still+closest"). Against the full flights: runs it ends that would have finished (status changed), time-outs
that came more than 0.05 m closer later (distance changed; distances to the box footprints at the 0.5 s samples),
and the simulated time saved.
"""
from __future__ import annotations

import argparse
import pickle
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))
STEP_S = 0.5  # the trajectory's sampling


def full_flights(cache: Path) -> list[tuple]:
    """(status, duration, t, xyz, obstacles) of each test's full flight, flown once and cached."""
    if cache.is_file():
        return pickle.loads(cache.read_bytes())
    from bench_stuck import DATA, fly  # the full pass of bench_stuck.py
    from surrealist_gym.fidelity.labels import load_labelled_set
    from surrealist_gym.sim.uav import decide_uav

    tests = list(load_labelled_set(DATA).tests)
    runs, _ = fly(tests, decide_uav(uav="px4-v1.12-sitl-iris").config, 2)
    flights = [(r.status, r.duration, np.asarray(r.trajectory.t), np.asarray(r.trajectory.xyz), test.obstacles)
               for r, test in zip(runs, tests)]
    cache.parent.mkdir(parents=True, exist_ok=True)
    cache.write_bytes(pickle.dumps(flights))
    return flights


def first_still(t, xyz, closest, window_s: float, radius_m: float, rule: str):
    """The sample index at which the rule first holds, or None."""
    w = int(round(window_s / STEP_S))
    for i in range(w, len(t)):
        seg = xyz[i - w:i + 1]
        if seg[:, 2].min() < 1.0:
            continue
        if np.hypot(*(seg[:, :2] - seg[:, :2].mean(0)).T).max() > radius_m:
            continue
        if rule == "still+closest" and closest[:i + 1].min() < closest[:i - w + 1].min() - 0.01:
            continue
        return i
    return None


def main(argv=None) -> int:
    from surrealist_gym.geometry import obstacle_distances

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cache", type=Path, default=Path("results/stuck-full.pkl"))
    args = parser.parse_args(argv)
    flights = full_flights(args.cache)
    closest = [obstacle_distances(xyz[:, :2], obstacles).min(1) if len(xyz) else np.zeros(0)
               for _, _, _, xyz, obstacles in flights]
    total = sum(f[1] for f in flights)
    print(f"{len(flights)} full flights, {sum(f[0] == 'timeout' for f in flights)} time-outs")
    for rule in ("still", "still+closest"):
        for window in (20, 30, 60, 90):
            for radius in (0.5, 1.0, 2.0):
                ended = status = moved = 0
                saved = 0.0
                for (st, duration, t, xyz, _), dd in zip(flights, closest):
                    i = first_still(t, xyz, dd, window, radius, rule) if len(t) > 2 else None
                    if i is None:
                        continue
                    ended += 1
                    if st != "timeout":
                        status += 1
                        continue
                    moved += int(dd[i + 1:].size > 0 and dd[i + 1:].min() < dd[:i + 1].min() - 0.05)
                    saved += duration - t[i]
                print(f"{rule:14} W {window:3} s R {radius:3} m: ended {ended:4}, status changed {status:3}, "
                      f"distance changed {moved:3}, simulated time saved {saved / total:.0%}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
