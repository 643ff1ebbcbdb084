"""Steady speed on the mission line: PX4's 24 rilast trajectories against our UAV with a given heading offset.

    python benchmarks/lab/2026-11-24-sitl-pace/online_speed.py dev -16 0    # dev = runs 0-2, held = 3-4

Each value after the split is a ``planner.heading_offset_deg`` of the px4-v1.12-sitl-iris profile (its own: -16).
The study first varied the planner's cruise speed cap (``cruise_speed_max``), a setting since removed; that version
of this script is at commit dd02d7e.

Windows of 0.5 s from 8 s after reaching altitude until the flight first leaves the line by 0.3 m.
"""
import csv, collections, json, sys, dataclasses, numpy as np
import surrealist_gym as sg
from surrealist_gym.testcase import Obstacle
from surrealist_gym.sim.profiles import load_profile
from pathlib import Path
DATA = str(Path(__file__).resolve().parents[3].parent / "shared" / "data")
T = collections.defaultdict(list)
for r in csv.DictReader(open(DATA + '/competition/rilast-mission1/trajectories.csv')):
    T[r['test_id']].append((int(r['sample']), float(r['x']), float(r['y']), float(r['z'])))
tests = {r['test_id']: r for r in csv.DictReader(open(DATA + '/competition/rilast-mission1/tests.csv'))}
u = np.array([3.3127, 53.103]) / np.hypot(3.3127, 53.103)
def online(t, x, y, z):
    v = np.hypot(np.diff(x), np.diff(y)) / np.diff(t)
    hi = np.where(z > 9.5)[0]
    if not len(hi): return []
    t0 = t[hi[0]] + 8.0
    ct = np.abs(-u[1] * x + u[0] * y)
    along = u[0] * x + u[1] * y
    off = np.where((ct > 0.3) & (t > t[hi[0]]))[0]
    t1 = t[off[0]] if len(off) else t[-1]
    m = (t[:-1] > t0) & (t[:-1] < t1) & (z[:-1] > 9.5) & (along[:-1] < 45)
    return list(v[m])
split = sys.argv[1]
ids = [k for k in T if (int(k.split('_run')[1].split('_')[0]) <= 2) == (split == 'dev')]
px = []
for k in ids:
    a = np.array(sorted(T[k])); px += online(a[:, 0] * 0.5, a[:, 1], a[:, 2], a[:, 3])
print(split, 'PX4 on-line speed: median %.2f p25 %.2f p75 %.2f n=%d' % (np.median(px), np.percentile(px, 25), np.percentile(px, 75), len(px)))
base = sg.load_test(DATA + '/competition/case_studies/mission1.yaml')
prof = load_profile('px4-v1.12-sitl-iris').sim_config()
for L in [float(v) for v in sys.argv[2:]]:
    cfg = dataclasses.replace(prof, avoidance_config=dataclasses.replace(prof.avoidance_config, heading_offset_deg=L))
    ours = []
    for k in ids:
        t = base.with_obstacles([Obstacle(**o) for o in json.loads(tests[k]['obstacles'])])
        r = sg.simulate(t, runs=1, seed=0, config=cfg)[0]
        tr = r.trajectory
        ours += online(tr.t, tr.x, tr.y, tr.z)
    print(' offset %.2f ours on-line: median %.2f p25 %.2f p75 %.2f n=%d' % (L, np.median(ours), np.percentile(ours, 25), np.percentile(ours, 75), len(ours)))
