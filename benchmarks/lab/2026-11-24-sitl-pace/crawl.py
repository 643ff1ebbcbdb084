"""Crawl episodes: seconds below 0.5 m/s at altitude, PX4's 24 rilast trajectories against our UAV.

    python benchmarks/lab/2026-11-24-sitl-pace/crawl.py                     # the SITL profile
    python benchmarks/lab/2026-11-24-sitl-pace/crawl.py '{"noise": {}}'     # with the default (PX4 Vision) noise
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
def stats(t, x, y, z):
    v = np.hypot(np.diff(x), np.diff(y)) / np.diff(t)
    hi = np.where(z > 9.0)[0]
    m = np.zeros(len(v), bool); m[hi[0]+4:hi[-1]-4] = True
    slow = (v < 0.5) & m
    return slow.sum() * 0.5, m.sum() * 0.5
changes = json.loads(sys.argv[1]) if len(sys.argv) > 1 else {}
base = sg.load_test(DATA + '/competition/case_studies/mission1.yaml')
cfg = load_profile('px4-v1.12-sitl-iris').sim_config()
plan = changes.pop('planner', {})
if 'noise' in changes:
    from surrealist_gym.sim.config import NoiseConfig
    changes['noise'] = NoiseConfig(**changes['noise'])
if plan: cfg = dataclasses.replace(cfg, avoidance_config=dataclasses.replace(cfg.avoidance_config, **plan))
cfg = dataclasses.replace(cfg, **changes)
for k in sorted(T):
    a = np.array(sorted(T[k])); ps, pt = stats(a[:, 0] * 0.5, a[:, 1], a[:, 2], a[:, 3])
    t = base.with_obstacles([Obstacle(**o) for o in json.loads(tests[k]['obstacles'])])
    r = sg.simulate(t, runs=1, seed=0, config=cfg)[0]; tr = r.trajectory
    os_, ot = stats(tr.t, tr.x, tr.y, tr.z)
    print(f"{k:18s} PX4 slow {ps:5.0f}/{pt:5.0f}s   ours slow {os_:5.0f}/{ot:5.0f}s")
