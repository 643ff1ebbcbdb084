"""Does our UAV pass wide because of the plan or the flight? Closest approach of the planner's setpoints, first
tree nodes and the flown path, on rilast tests where PX4 passed close.

    python benchmarks/lab/2026-11-24-sitl-pace/plan_vs_flown.py ga_one_point_run4_0 random_run1_69
"""
import json, csv, sys, math, numpy as np
import surrealist_gym as sg
from surrealist_gym.testcase import Obstacle
from surrealist_gym.sim.profiles import load_profile
from surrealist_gym.sim.avoidance.px4 import local_planner as px4_avoidance
from surrealist_gym.geometry import competition_distance, obstacle_distances
from pathlib import Path
DATA = str(Path(__file__).resolve().parents[3].parent / "shared" / "data")
rows = {r['test_id']: r for r in csv.DictReader(open(DATA + '/competition/rilast-mission1/tests.csv'))}
for tid in sys.argv[1:]:
    obs = [Obstacle(**o) for o in json.loads(rows[tid]['obstacles'])]
    t = sg.load_test(DATA + '/competition/case_studies/mission1.yaml').with_obstacles(obs)
    sps, nodes = [], []
    orig = px4_avoidance.Px4LocalPlanner.update
    def upd(self, *a, **k):
        out = orig(self, *a, **k); sps.append(out.position)
        if len(out.path) > 1: nodes.append(out.path[1])
        return out
    px4_avoidance.Px4LocalPlanner.update = upd
    r = sg.simulate(t, runs=1, seed=0, config=load_profile('px4-v1.12-sitl-iris').sim_config())[0]
    px4_avoidance.Px4LocalPlanner.update = orig
    d_flown = obstacle_distances(r.true_xyz[:, :2], obs, 2).min()
    d_sp = obstacle_distances(np.array(sps)[:, :2], obs, 2).min()
    d_node = obstacle_distances(np.array(nodes)[:, :2], obs, 2).min() if nodes else float('nan')
    print(f"{tid}: PX4 {float(rows[tid]['px4_min_distance_2d']):.2f}  ours flown {d_flown:.2f}  setpoints {d_sp:.2f}  first nodes {d_node:.2f}  competition {competition_distance(r.trajectory, obs):.2f}")
