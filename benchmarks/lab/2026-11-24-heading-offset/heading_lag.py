"""PX4's heading against its direction of motion on the 24 rilast trajectories, and ours on the same tests.

    python benchmarks/lab/2026-11-24-heading-offset/heading_lag.py          # PX4 only
    python benchmarks/lab/2026-11-24-heading-offset/heading_lag.py --ours   # and our UAV (px4-v1.12-sitl-iris)

Lag = direction of motion - heading over 0.5 s windows at altitude (> 8 m), moving (> 0.3 m/s) and not turning
(|yaw rate| < 3 deg/s); clockwise positive. The trajectories' yaw is relative to the first sample (the Iris spawns
facing east, +y); ours is converted to the same convention.
"""
import csv, json, math, sys
from pathlib import Path

import numpy as np

import surrealist_gym as sg
from surrealist_gym.sim.profiles import load_profile
from surrealist_gym.sim.runner import initial_yaw
from surrealist_gym.testcase import Obstacle

DATA = Path(__file__).resolve().parents[3].parent / "shared" / "data"


def lags(p):
    """p: (N, 4) x north, y east, z up, yaw (rad, 0 = east, clockwise) at 2 Hz -> lags [deg]."""
    out = []
    for a, b in zip(p[:-1], p[1:]):
        dx, dy = b[0] - a[0], b[1] - a[1]
        rate = math.degrees(math.remainder(b[3] - a[3], 2 * math.pi)) * 2
        if 2 * math.hypot(dx, dy) < 0.3 or a[2] < 8 or abs(rate) > 3:
            continue
        course = math.atan2(-dx, dy)  # from east, clockwise (toward -x, south)
        out.append(math.degrees(math.remainder(course - a[3], 2 * math.pi)))
    return np.array(out)


tests = {r["test_id"]: r for r in csv.DictReader(open(DATA / "competition/rilast-mission1/tests.csv"))}
flights = {}
for r in csv.DictReader(open(DATA / "competition/rilast-mission1/trajectories.csv")):
    flights.setdefault(r["test_id"], []).append([float(r[k]) for k in ("x", "y", "z", "yaw")])
ours = "--ours" in sys.argv
base = sg.load_test(DATA / "competition/case_studies/mission1.yaml")
config = load_profile("px4-v1.12-sitl-iris").sim_config()
start = initial_yaw(base.mission)
all_px4, all_ours = [], []
for tid, p in sorted(flights.items()):
    lp = lags(np.array(p))
    if len(lp) == 0:
        continue
    all_px4 += list(lp)
    line = f"{tid:18s} PX4 lag median {np.median(lp):5.1f} deg (n={len(lp)})"
    if ours:
        run = sg.simulate(base.with_obstacles([Obstacle(**o) for o in json.loads(tests[tid]["obstacles"])]),
                          runs=1, seed=0, config=config)[0]
        tr = run.trajectory
        t = np.arange(tr.t[0], tr.t[-1], 0.5)
        idx = np.searchsorted(tr.t, t)
        heading = np.interp(t, tr.t, np.unwrap(tr.heading)) if tr.heading is not None else None
        # Trajectory.heading is relative to the first sample; ours starts facing the mission's end, PX4's east
        q = np.column_stack([tr.xyz[idx, 0], tr.xyz[idx, 1], tr.xyz[idx, 2], heading + start - math.pi / 2])
        lo = lags(q)
        all_ours += list(lo)
        line += f" | ours {np.median(lo):5.1f} deg (n={len(lo)})"
    print(line, flush=True)
print(f"PX4: median {np.median(all_px4):.1f} deg, p10-p90 {np.percentile(all_px4, 10):.1f} to "
      f"{np.percentile(all_px4, 90):.1f}, n={len(all_px4)}")
if ours:
    print(f"ours: median {np.median(all_ours):.1f} deg, p10-p90 {np.percentile(all_ours, 10):.1f} to "
          f"{np.percentile(all_ours, 90):.1f}, n={len(all_ours)}")
