"""The close-region variants of ../2026-11-24-sitl-pace/variants.py with the camera's cloud reaching the planner
L seconds late (L first, then variants.py's arguments):

    python benchmarks/lab/2026-11-24-heading-offset/latency.py 0.5 dev close 2
"""
import sys, collections, runpy
from surrealist_gym.sim.avoidance.px4 import local_planner as px4_avoidance
L=float(sys.argv.pop(1))
orig=px4_avoidance.Px4LocalPlanner.update
def upd(self, t, pos, vel, yaw, goal, prev, hits, pitch=0.0):
    q=self.__dict__.setdefault('_q', collections.deque())
    q.append((t, hits))
    while len(q)>1 and q[1][0] <= t - L: q.popleft()
    h = q[0][1] if q[0][0] <= t - L else hits[:0]
    return orig(self, t, pos, vel, yaw, goal, prev, h, pitch)
px4_avoidance.Px4LocalPlanner.update=upd
sys.argv=[sys.argv[0]]+sys.argv[1:]
runpy.run_path('benchmarks/lab/2026-11-24-sitl-pace/variants.py', run_name='__main__')
