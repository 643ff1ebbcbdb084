"""The planner cycle kernel (:mod:`surrealist_gym.sim.avoidance.px4.cycle`) against the readable
:class:`~surrealist_gym.sim.avoidance.px4.local_planner.Px4LocalPlanner` on the cycles of real flights: the same
bits."""
from __future__ import annotations

import csv
import json

import numpy as np
import pytest

from surrealist_gym import Obstacle, load_test
from surrealist_gym.sim import simulate
from surrealist_gym.sim.avoidance.px4 import cycle as kc
from surrealist_gym.sim.avoidance.px4.local_planner import Px4LocalPlanner
from surrealist_gym.sim.avoidance.px4.settings import MAX_NODES
from surrealist_gym.sim.uav import decide_uav
from tests.conftest import CASE_STUDIES, SHARED_DATA, fly_the_python_outer_loop

RILAST = SHARED_DATA / "competition" / "rilast-mission1" / "tests.csv"


def _rilast(test_id: str):
    with open(RILAST, newline="") as f:
        row = next(r for r in csv.DictReader(f) if r["test_id"] == test_id)
    return load_test(CASE_STUDIES / "mission1.yaml").with_obstacles(
        [Obstacle(**o) for o in json.loads(row["obstacles"])])


def _recorded_cycles(test, monkeypatch):
    """Every Px4LocalPlanner.update of one run of ``test`` (its UAV): the planner, then each call's arguments and
    output."""
    calls, planners = [], []
    update = Px4LocalPlanner.update

    def recording(self, t, position, velocity, yaw, goal, prev_goal, hits, pitch=0.0):
        if not planners:
            planners.append(self)
        args = (t, tuple(map(float, position)), tuple(map(float, velocity)), float(yaw),
                tuple(map(float, goal)), tuple(map(float, prev_goal)),
                np.array(hits, dtype=np.float64).reshape(-1, 3), float(pitch))
        out = update(self, t, position, velocity, yaw, goal, prev_goal, hits, pitch)
        calls.append((args, out))
        return out

    monkeypatch.setattr(Px4LocalPlanner, "update", recording)
    fly_the_python_outer_loop(monkeypatch)
    simulate(test, runs=1, seed=0, config=decide_uav(test).config)
    monkeypatch.undo()
    return planners[0], calls


@pytest.mark.parametrize("test_id", ["random_run3_194", "random_run0_0"])
def test_the_kernel_gives_the_class_bits_over_a_flight(test_id, monkeypatch):
    """A flight of a rilast test (2 and 3 boxes) on the SITL Iris: each of its planner cycles replayed through the
    kernel from the initial state gives the class's setpoint, yaw, state, speed, point count and tree path, bit for
    bit."""
    planner, calls = _recorded_cycles(_rilast(test_id), monkeypatch)
    assert len(calls) > 100 and sum(out.path.shape[0] > 0 for _, out in calls) > 20  # trees were built
    settings, consts = planner._settings, kc.constants(planner)
    cloud, age, path, state = np.empty((0, 3)), np.empty(0), np.empty((MAX_NODES, 3)), kc.initial_state()
    for i, (args, want) in enumerate(calls):
        t, position, velocity, yaw, goal, prev_goal, hits, pitch = args
        cloud, age, x, y, z, yaw_sp, code, speed, built, n = kc.cycle(
            cloud, age, path, state, settings, consts, t, position, velocity, yaw, goal, prev_goal, hits, pitch)
        assert (x, y, z) == want.position, i
        assert yaw_sp == want.yaw and speed == want.speed and n == want.points, i
        assert ("try_path" if code == kc.TRY_PATH else "direct") == want.state, i
        got_path = path[:int(state[kc.PATH_LEN])] if built else np.empty((0, 3))
        assert np.array_equal(got_path, want.path), i


def test_point_on_path_and_line_projection():
    """The waypoint generator's helpers, which the class and the kernel share, against direct computations."""
    path = np.array([[0.0, 0.0, 0.0], [3.0, 4.0, 0.0], [3.0, 4.0, 2.0]])
    assert kc.point_on_path(path, 3, 2.5) == (True, 1.5, 2.0, 0.0)
    assert kc.point_on_path(path, 3, 6.0) == (True, 3.0, 4.0, 1.0)
    assert not kc.point_on_path(path, 3, 7.5)[0]
    assert kc.closest_on_line(1.0, 5.0, 0.0, 0.0, 10.0, 0.0, 2.0) == (True, 1.0, 0.0)
    assert not kc.closest_on_line(1.0, 1.0, 0.0, 0.0, 10.0, 0.0, 2.0)[0]  # within the band
    assert not kc.closest_on_line(1.0, 5.0, 0.0, 0.0, 0.0, 0.0, 2.0)[0]  # no line


def test_a_hovering_planner_keeps_its_tree_within_the_reuse_radius(monkeypatch):
    """``SimConfig.tree_reuse_m``'s rule on a flight's recorded cycles: at a cycle with a tree, the next cycle from
    the same position toward the same goal keeps that path (no build; its time is now), up to the cycle limit in a row;
    a position beyond the radius, another goal, or the limit reached builds again, and the path built equals the one
    a planner without reuse builds there."""
    planner, calls = _recorded_cycles(_rilast("random_run3_194"), monkeypatch)
    settings = planner._settings
    fresh = kc.constants(planner)
    reuse = kc.constants(planner, 0.2, 2)
    i = next(i for i, (args, out) in enumerate(calls)  # a tree built from a scan that saw a box within 12 m
             if out.path.shape[0] > 0 and args[6].shape[0] > 0
             and np.linalg.norm(args[6] - np.array(args[1]), axis=1).min() < 12.0)
    t, position, velocity, yaw, goal, prev_goal, hits, pitch = calls[i][0]

    def run(consts, steps):
        """The recorded cycles up to ``i`` (a tree every cycle), then ``steps`` (dt, position, goal) with
        ``consts``."""
        cloud, age, path, state = np.empty((0, 3)), np.empty(0), np.empty((MAX_NODES, 3)), kc.initial_state()
        for args, _ in calls[:i + 1]:
            cloud, age, *_ = kc.cycle(cloud, age, path, state, settings, fresh, *args)
        built = []
        for dt, pos, g in steps:
            cloud, age, *_, b, _ = kc.cycle(cloud, age, path, state, settings, consts, t + dt, pos, velocity, yaw,
                                            g, prev_goal, hits, pitch)
            built.append(b)
        return built, path[:int(state[kc.PATH_LEN])].copy(), state

    near = (position[0] + 0.1, position[1], position[2])
    far = (position[0] + 0.3, position[1], position[2])
    other = (goal[0] + 1.0, goal[1], goal[2])
    built, kept, state = run(reuse, [(0.1, near, goal), (0.2, near, goal), (0.3, near, goal)])
    assert built == [False, False, True]  # two kept, then the limit
    assert state[kc.PATH_T] == t + 0.3
    built, kept, state = run(reuse, [(0.1, near, goal)])
    assert built == [False] and state[kc.PATH_T] == t + 0.1 and np.array_equal(kept[0], position)
    assert run(reuse, [(0.1, far, goal)])[0] == [True]
    assert run(reuse, [(0.1, near, other)])[0] == [True]
    built, path, _ = run(reuse, [(0.1, far, goal)])
    assert np.array_equal(path, run(fresh, [(0.1, far, goal)])[1])
    assert run(fresh, [(0.1, near, goal)])[0] == [True]  # without reuse: a tree every cycle
