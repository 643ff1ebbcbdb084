"""Median times of DepthSensor.scan and LocalPlanner.update [us], and of a whole closed-loop detour.

Run: ``python benchmarks/bench_avoidance.py``. The closed loop is kinematic (position += velocity * dt, 20 Hz)
on case0's leg with the case0 box, then with a 2.5 x 12 x 2.5 m container across the leg.
"""
from __future__ import annotations

import math
import time

import numpy as np

from surrealist_gym.sim.avoidance.reactive import LocalPlanner
from surrealist_gym.sim.sensing.sensor import DepthSensor
from surrealist_gym.testcase import Obstacle, Shape

START, GOAL = np.array([0.0, 0.0, 3.0]), np.array([-16.6, 6.9, 3.0])
HEADING = math.degrees(math.atan2(GOAL[1], GOAL[0]))
SCENES = {
    "case0 box": [Obstacle(3.0, 3.0, 3.0, -8.64, 1.74, 0.0, 158.8)],
    "container": [Obstacle(2.5, 12.0, 2.5, -8.3 - 2.0 * math.sin(math.radians(HEADING)),
                           3.45 + 2.0 * math.cos(math.radians(HEADING)), 0.0, HEADING)],
    "3 obstacles": [Obstacle(3.0, 3.0, 3.0, -5.0, 2.3), Obstacle(2.0, 2.0, 5.0, -11.5, 3.3, shape=Shape.CYLINDER),
                    Obstacle(2.0, 6.0, 4.0, -9.0, -3.0, 0.0, 30.0)],
}


def run(obstacles, dt=0.05, steps=1000):
    sensor, planner = DepthSensor(obstacles), LocalPlanner()
    pos, vel, yaw = START.copy(), np.zeros(3), math.atan2(GOAL[1], GOAL[0])
    rng = np.random.default_rng(0)
    t_scan, t_update = [], []
    t0 = time.perf_counter()
    for i in range(steps):
        a = time.perf_counter()
        hits = sensor.scan(pos, yaw, rng)
        b = time.perf_counter()
        out = planner.update(i * dt, pos, vel, GOAL, hits, max_speed=5.0)
        c = time.perf_counter()
        t_scan.append(b - a)
        t_update.append(c - b)
        vel, yaw = np.array(out.velocity), out.yaw
        pos = pos + vel * dt
        if np.linalg.norm(pos - GOAL) < 0.1:
            break
    total = time.perf_counter() - t0
    return np.median(t_scan) * 1e6, np.median(t_update) * 1e6, max(t_update) * 1e6, i + 1, total


def main():
    run(SCENES["case0 box"])  # compile / load the numba cache
    print(f"{'scene':12s} {'scan us':>8s} {'update us':>10s} {'max upd us':>11s} {'steps':>6s} {'loop ms':>8s}")
    for name, obstacles in SCENES.items():
        scan, update, worst, steps, total = run(obstacles)
        print(f"{name:12s} {scan:8.1f} {update:10.1f} {worst:11.1f} {steps:6d} {total * 1e3:8.1f}")


if __name__ == "__main__":
    main()
