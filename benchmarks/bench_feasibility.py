"""The feasibility check (surrealist_gym.competition.feasibility) on walled-off layouts and PX4's labelled flights, and
its time.

Run from the project root::

    python benchmarks/bench_feasibility.py [--quick] [--fly-all] [--gap-sweep]

Prints: how many layouts of ``tests/data/walled_off`` are rejected (target: all) with their reasons; how many
rilast-mission1 layouts PX4 flew to the end (``px4_result == flown``) are rejected (target: none), how many
``no_result`` ones (mostly 500 s timeouts) and CAMBA soft failures are; the check's time per test against one
simulation (the px4-v1.12-sitl-iris profile, measured in the same run) of a flown rilast test and of a walled-off
layout. ``--fly-all`` flies every walled-off layout in the simulator; ``--gap-sweep`` flies mission1 through an
80 m wall with one gap of several widths. Then, unless ``--quick``, the measurements behind the defaults
(docs/feasibility.md): how far the recorded rilast flights stray from their track and the narrowest gap they cross,
the widest detour a flown layout needs to keep its labelled distance, and the margins of the defaults on the flown
layouts.
"""
from __future__ import annotations

import argparse
import csv
import itertools
import statistics
import sys
import time
import warnings
from collections import defaultdict
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
WALLED_OFF = ROOT / "tests" / "data" / "walled_off"
COMPETITION = ROOT.parent / "shared" / "data" / "competition"
RILAST = COMPETITION / "rilast-mission1"
PROFILE = "px4-v1.12-sitl-iris"


def _bisect(ok, lo: float, hi: float, steps: int = 20) -> float:
    """The smallest x in [lo, hi] with ok(x), for ok monotone (False below, True above) [same unit as lo, hi]."""
    for _ in range(steps):
        mid = (lo + hi) / 2
        lo, hi = (lo, mid) if ok(mid) else (mid, hi)
    return hi


def _calibration(rilast, camba, cfg) -> None:
    from shapely.geometry import LineString, Point, Polygon

    from surrealist_gym.competition.feasibility import infeasible

    start, goal = (0.0, 0.0), next(it for it in rilast.tests[0].mission.items if it.command.name == "LAND")
    track = LineString([start, (goal.x, goal.y)])
    tests = {lab.test_id: t for lab, t in zip(rilast.labels, rilast.tests)}
    paths = defaultdict(list)
    with open(RILAST / "trajectories.csv", newline="") as f:
        for row in csv.DictReader(f):
            paths[row["test_id"]].append((float(row["x"]), float(row["y"])))
    stray = max((max(track.distance(Point(p)) for p in path), tid) for tid, path in paths.items())
    crossed = []
    for tid, path in paths.items():
        boxes = [Polygon(o.footprint()) for o in tests[tid].obstacles]
        for a, b in itertools.combinations(boxes, 2):
            if a.distance(b) > 0 and LineString(path).intersects(LineString(_shortest(a, b))):
                crossed.append((a.distance(b), tid))
    print(f"recorded rilast flights ({len(paths)}): up to {stray[0]:.1f} m from the track ({stray[1]}); "
          f"{len(crossed)} crossings between two boxes, the narrowest gap {min(crossed)[0]:.2f} m ({min(crossed)[1]})")

    flown = [(lab, t) for lab, t in zip(rilast.labels, rilast.tests) if lab.result == "flown"]
    detours, idle = [], 0
    for lab, t in flown:
        boxes = [Polygon(o.footprint()) for o in t.obstacles]
        if lab.distance >= min(min(b.distance(Point(start)), b.distance(Point(goal.x, goal.y))) for b in boxes) - 0.05:
            idle += 1  # the label is the start's (or goal's) own distance to a box: the UAV did not fly the track
            continue
        c = max(lab.distance - 0.05, 0.0)
        detours.append((_bisect(lambda d: infeasible(t, replace(cfg, clearance_m=c, max_offset_m=d)) is None,
                                0.1, 200.0), lab.test_id, lab.distance))
    widest = max(detours)
    print(f"flown rilast layouts keeping their labelled distance ({len(detours)}; {idle} labels skipped: the "
          f"distance of the start or goal itself): the widest detour reaches {widest[0]:.1f} m from the track "
          f"({widest[1]}, {widest[2]:.2f} m)")

    accepted = flown + [(lab, t) for lab, t in zip(camba.labels, camba.tests)]
    most_c = min(_bisect(lambda c: infeasible(t, replace(cfg, clearance_m=c)) is not None, 0.0, 10.0)
                 for _, t in accepted)
    least_d = max(_bisect(lambda d: infeasible(t, replace(cfg, max_offset_m=d)) is None, 0.1, 100.0)
                  for _, t in accepted)
    timeouts = [t for lab, t in zip(rilast.labels, rilast.tests) if lab.result == "timeout"]
    first = min(_bisect(lambda c: infeasible(t, replace(cfg, clearance_m=c)) is not None, 0.0, 10.0)
                for t in timeouts)
    print(f"flown rilast + CAMBA layouts ({len(accepted)}) are all accepted for clearance_m < {most_c:.2f} m "
          f"(at max_offset_m {cfg.max_offset_m:g}) and for max_offset_m >= {least_d:.1f} m (at clearance_m "
          f"{cfg.clearance_m:g}); the first no_result layout is rejected from clearance_m {first:.2f} m, and at "
          f"{most_c - 0.01:.2f} m "
          f"{sum(infeasible(t, replace(cfg, clearance_m=most_c - 0.01)) is not None for t in timeouts)}"
          f"/{len(timeouts)} are")


def _gap_sweep(mission1, sim_cfg) -> None:
    """Two 38 x 2 m boxes across mission1's track at y = 25 m, `gap` apart on the track: which gaps the simulated
    PX4-Avoidance flies through within the 500 s timeout."""
    from surrealist_gym.testcase import Obstacle

    x = 3.31 * 25 / 53.1  # the track's x at y = 25 m
    for gap in (4.0, 6.0, 7.0, 8.0, 10.0):
        boxes = [Obstacle(38, 2, 20, x + side * (gap / 2 + 19), 25) for side in (-1, 1)]
        print(f"  gap {gap:4.1f} m: {_simulate_s(mission1.with_obstacles(boxes), sim_cfg)[1]}")


def _shortest(a, b):
    import shapely

    return shapely.shortest_line(a, b).coords


def _simulate_s(test, config) -> tuple[float, str]:
    from surrealist_gym.sim.runner import simulate

    start = time.perf_counter()
    run = simulate(test, runs=1, seed=0, config=config)[0]
    return time.perf_counter() - start, (f"{run.status.value} after {run.duration:.0f} s simulated, competition "
                                         f"distance {run.competition_distance:.2f} m")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="skip the calibration measurements")
    parser.add_argument("--fly-all", action="store_true", help="fly every walled-off layout in the simulator")
    parser.add_argument("--gap-sweep", action="store_true",
                        help="fly mission1 through an 80 m wall with one gap on the track, for several gap widths")
    args = parser.parse_args()
    if not RILAST.is_dir():
        sys.exit(f"needs the shared data folder {COMPETITION}")
    warnings.filterwarnings("ignore", message=".*MAV_CMD 530 is not supported.*")  # mission2/3's camera item

    from surrealist_gym.aerialist import load_test
    from surrealist_gym.competition.feasibility import FeasibilityConfig, infeasible
    from surrealist_gym.fidelity.labels import load_labelled_set
    from surrealist_gym.sim.profiles import load_profile

    cfg = FeasibilityConfig()
    print(f"{cfg}")
    shared = ROOT.parent / "shared" / "data" / "competition" / "case_studies"  # the files they name
    walled = {p.stem: load_test(p, allow_outside=[shared]) for p in sorted(WALLED_OFF.glob("*.yaml"))}
    reasons = {name: infeasible(t, cfg) for name, t in walled.items()}
    for name, reason in reasons.items():
        print(f"  {name:24s} {reason or 'ACCEPTED'}")
    print(f"walled-off layouts rejected: {sum(r is not None for r in reasons.values())}/{len(walled)} (target: all)")

    rilast = load_labelled_set(RILAST / "tests.csv")
    camba = load_labelled_set(COMPETITION / "camba-collection")
    checked: dict[str, list] = defaultdict(list)
    times = []
    for labels, tests in ((rilast.labels, rilast.tests), (camba.labels, camba.tests)):
        for lab, t in zip(labels, tests):
            start = time.perf_counter()
            reason = infeasible(t, cfg)
            times.append(time.perf_counter() - start)
            key = ("camba " if labels is camba.labels else "rilast ") + lab.result.replace("timeout", "no_result")
            checked[key].append((lab.test_id, reason))
    for key, rows in checked.items():
        rejected = [(tid, r) for tid, r in rows if r is not None]
        target = " (target: none)" if key.endswith("flown") else ""
        print(f"{key} layouts rejected: {len(rejected)}/{len(rows)}{target}")
        for tid, r in rejected:
            print(f"  {tid}: {r}")

    sim_cfg = load_profile(PROFILE).sim_config()
    flown_id, flown_test = next((lab.test_id, t) for lab, t in zip(rilast.labels, rilast.tests)
                                if lab.result == "flown")
    sim_flown, what_flown = _simulate_s(flown_test, sim_cfg)
    sim_walled, what_walled = _simulate_s(walled["m1_diamond_wall_narrow"], sim_cfg)
    check = statistics.fmean(times)
    print(f"check: {check * 1e3:.2f} ms per test (mean of {len(times)}; median {statistics.median(times) * 1e3:.2f} "
          f"ms, max {max(times) * 1e3:.1f} ms)")
    print(f"one simulation ({PROFILE}): {sim_flown:.1f} s for {flown_id} ({what_flown}), "
          f"{sim_walled:.1f} s for m1_diamond_wall_narrow ({what_walled}); the check costs "
          f"{check / sim_flown:.1e} and {check / sim_walled:.1e} of them")
    if args.fly_all:
        for name, t in walled.items():
            print(f"  fly {name:24s} {_simulate_s(t, sim_cfg)[1]}")
    if args.gap_sweep:
        _gap_sweep(walled["m1_diamond_wall_narrow"], sim_cfg)
    if not args.quick:
        _calibration(rilast, camba, cfg)


if __name__ == "__main__":
    main()
