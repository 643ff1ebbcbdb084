"""LocalPlanner: free flight, steering and slowing near obstacles, memory, and closed-loop detours."""
from __future__ import annotations

import math

import numpy as np
import pytest

from surrealist_gym.geometry import obstacle_distances
from surrealist_gym.sim.avoidance.reactive import AvoidanceConfig, LocalPlanner, PlannerOutput, YawMode
from surrealist_gym.sim.sensing.sensor import DepthSensor, DepthSensorConfig
from surrealist_gym.testcase import Obstacle, Shape

NO_HITS = np.empty((0, 3))
START, GOAL = (0.0, 0.0, 3.0), (-16.6, 6.9, 3.0)  # case0's mission leg
HEADING = math.degrees(math.atan2(GOAL[1], GOAL[0]))
CASE0_BOX = Obstacle(3.0, 3.0, 3.0, -8.64, 1.74, 0.0, 158.8)
# a 2.5 x 12 x 2.5 m container across the leg, its middle 2 m to the right of the straight line
_RIGHT = math.radians(HEADING + 90.0)
CONTAINER = Obstacle(2.5, 12.0, 2.5, -8.3 + 2.0 * math.cos(_RIGHT), 3.45 + 2.0 * math.sin(_RIGHT), 0.0, HEADING)


def test_no_hits_flies_straight_at_the_goal_at_max_speed():
    planner = LocalPlanner()
    out = planner.update(0.0, (1.0, 2.0, 3.0), (0.0, 0.0, 0.0), (11.0, 12.0, 3.0), NO_HITS, max_speed=4.0)
    assert isinstance(out, PlannerOutput)
    np.testing.assert_allclose(out.velocity, (4.0 / math.sqrt(2), 4.0 / math.sqrt(2), 0.0), atol=1e-12)
    assert out.yaw == pytest.approx(math.pi / 4)
    np.testing.assert_allclose(out.waypoint, (1.0 + math.sqrt(2), 2.0 + math.sqrt(2), 3.0), atol=1e-12)
    # without max_speed: the configured cruise speed, in 3-D toward a higher goal
    out = planner.update(0.05, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, -30.0, 40.0), NO_HITS)
    np.testing.assert_allclose(out.velocity, (0.0, -3.0, 4.0), atol=1e-12)


def test_brakes_near_the_goal_and_stops_on_it():
    planner = LocalPlanner(AvoidanceConfig(goal_brake_accel=2.0))
    out = planner.update(0.0, (0.0, 0.0, 3.0), (0.0, 0.0, 0.0), (1.0, 0.0, 3.0), NO_HITS, max_speed=5.0)
    assert out.velocity[0] == pytest.approx(2.0)  # sqrt(2 * 2 * 1)
    out = planner.update(0.1, (1.0, 0.0, 3.0), (0.0, 0.0, 0.0), (1.0, 0.0, 3.0), NO_HITS, max_speed=5.0)
    assert out.velocity == (0.0, 0.0, 0.0)


def _scan_box_ahead(distance=6.0):
    wall = Obstacle(1.0, 8.0, 5.0, distance + 0.5, 0.0)
    return wall, DepthSensor([wall]).scan((0.0, 0.0, 3.0), 0.0)


def test_wall_on_the_line_makes_it_turn_and_slow_down():
    _, hits = _scan_box_ahead()
    planner = LocalPlanner()
    out = planner.update(0.0, (0.0, 0.0, 3.0), (5.0, 0.0, 0.0), (20.0, 0.0, 3.0), hits, max_speed=5.0)
    vx, vy, vz = out.velocity
    speed = math.hypot(vx, vy)
    assert speed == pytest.approx(planner.config.avoid_speed)
    assert abs(math.degrees(math.atan2(vy, vx))) > 30.0  # steers to a side of the 8 m wide wall
    assert abs(vz) < 1e-12
    assert out.yaw == pytest.approx(math.atan2(vy, vx))
    # the speed recovers with distance: far obstacles only ramp it down
    far = Obstacle(1.0, 1.0, 5.0, 10.5, 4.0)  # ~10.5 m away, inside the 8-12 m slow-down ramp
    hits = DepthSensor([far], DepthSensorConfig(range_max=15.0)).scan((0.0, 0.0, 3.0), 0.0)
    out = LocalPlanner().update(0.0, (0.0, 0.0, 3.0), (5.0, 0.0, 0.0), (20.0, 0.0, 3.0), hits, max_speed=5.0)
    assert planner.config.avoid_speed < math.hypot(*out.velocity[:2]) < 5.0


def test_memory_remembers_out_of_view_points_then_forgets_them():
    _, hits = _scan_box_ahead()
    planner = LocalPlanner(AvoidanceConfig(memory_time=2.0))
    first = planner.update(0.0, (0.0, 0.0, 3.0), (0.0, 0.0, 0.0), (20.0, 0.0, 3.0), hits, max_speed=5.0)
    assert planner.memory_size > 0
    again = planner.update(1.0, (0.0, 0.0, 3.0), (0.0, 0.0, 0.0), (20.0, 0.0, 3.0), NO_HITS, max_speed=5.0)
    assert math.hypot(*again.velocity) == pytest.approx(planner.config.avoid_speed)
    assert np.sign(again.velocity[1]) == np.sign(first.velocity[1])
    later = planner.update(2.5, (0.0, 0.0, 3.0), (0.0, 0.0, 0.0), (20.0, 0.0, 3.0), NO_HITS, max_speed=5.0)
    assert planner.memory_size == 0
    np.testing.assert_allclose(later.velocity, (5.0, 0.0, 0.0))
    planner.update(3.0, (0.0, 0.0, 3.0), (0.0, 0.0, 0.0), (20.0, 0.0, 3.0), hits, max_speed=5.0)
    planner.reset()
    assert planner.memory_size == 0


def test_stops_when_every_direction_is_blocked():
    ring = np.array([(2.0 * math.cos(a), 2.0 * math.sin(a), 3.0) for a in np.radians(np.arange(0, 360, 3))])
    out = LocalPlanner(AvoidanceConfig(safety_margin=2.5)).update(0.0, (0.0, 0.0, 3.0), (0.0, 0.0, 0.0),
                                                                   (20.0, 0.0, 3.0), ring, max_speed=5.0)
    assert math.hypot(*out.velocity[:2]) == 0.0


LATERAL = AvoidanceConfig(vertical_margin=0.0)  # lateral detours only (no rising over low obstacles)


def fly(obstacles, config=AvoidanceConfig(), steps=900, dt=0.05, noise_seed=None):
    """Kinematic closed loop at 20 Hz: scan at the commanded yaw, plan, position += velocity * dt."""
    sensor = DepthSensor(obstacles, DepthSensorConfig())
    planner = LocalPlanner(config)
    rng = None if noise_seed is None else np.random.default_rng(noise_seed)
    pos, vel = np.array(START), np.zeros(3)
    yaw = math.atan2(GOAL[1] - START[1], GOAL[0] - START[0])
    path, speeds = [pos.copy()], []
    for i in range(steps):
        out = planner.update(i * dt, pos, vel, GOAL, sensor.scan(pos, yaw, rng), max_speed=5.0)
        vel, yaw = np.array(out.velocity), out.yaw
        pos = pos + vel * dt
        path.append(pos.copy())
        speeds.append(math.hypot(vel[0], vel[1]))
        if np.linalg.norm(pos - GOAL) < 0.1:
            break
    return np.array(path), np.array(speeds)


def _lateral(path):
    """Signed offset of each point from the straight start-goal line [m] (positive to the right)."""
    g = np.subtract(GOAL[:2], START[:2])
    g /= np.linalg.norm(g)
    return (path[:, :2] - START[:2]) @ np.array([-g[1], g[0]])


@pytest.mark.parametrize("obstacle", [CASE0_BOX, CONTAINER], ids=["case0-box", "container"])
def test_closed_loop_detour_reaches_the_goal_with_clearance(obstacle):
    path, speeds = fly([obstacle], config=LATERAL)
    assert np.linalg.norm(path[-1] - GOAL) < 0.1
    clearance = obstacle_distances(path, [obstacle], dims=3).min()
    assert clearance > 0.5
    lateral = _lateral(path)
    assert np.abs(lateral).max() > 1.5  # a sideways detour...
    assert np.ptp(path[:, 2]) < 1e-9  # ...not over the top
    assert np.median(speeds) == pytest.approx(0.75, abs=0.05)  # the planner sets the pace
    steps = np.diff(path[:, :2], axis=0)
    assert np.abs(np.diff(np.sign(np.round(lateral, 6)))).max() < 2  # stays on one side: no dithering
    assert (np.linalg.norm(steps, axis=1) <= 5.0 * 0.05 + 1e-9).all()


def test_closed_loop_with_several_obstacles_and_noise():
    obstacles = [Obstacle(3.0, 3.0, 3.0, -5.0, 2.3), Obstacle(2.0, 2.0, 5.0, -11.5, 3.3, shape=Shape.CYLINDER)]
    path, _ = fly(obstacles, config=LATERAL, noise_seed=1)
    assert np.linalg.norm(path[-1] - GOAL) < 0.1
    assert obstacle_distances(path, obstacles, dims=3).min() > 0.5


def test_rises_over_a_low_obstacle_but_not_over_a_tall_one():
    path, _ = fly([CASE0_BOX], steps=1400)  # default vertical_margin 1.5 m: the box top is 3 m
    assert 3.5 < path[:, 2].max() <= 3.0 + 1.5 + 0.05
    assert np.linalg.norm(path[-1] - GOAL) < 0.1
    tall = Obstacle(CASE0_BOX.l, CASE0_BOX.w, 20.0, CASE0_BOX.x, CASE0_BOX.y, 0.0, CASE0_BOX.r)
    path, _ = fly([tall])
    assert np.ptp(path[:, 2]) < 1e-9 and np.linalg.norm(path[-1] - GOAL) < 0.1


def test_closed_loop_is_deterministic():
    a, _ = fly([CASE0_BOX], noise_seed=5)
    b, _ = fly([CASE0_BOX], noise_seed=5)
    np.testing.assert_array_equal(a, b)
    c, _ = fly([CASE0_BOX], config=AvoidanceConfig(yaw_mode=YawMode.GOAL))
    assert np.linalg.norm(c[-1] - GOAL) < 0.1


@pytest.mark.parametrize("bad", [dict(avoid_speed=0.0), dict(bin_deg=7.0), dict(elevation_bands_deg=()),
                                 dict(memory_time=-1.0), dict(yaw_mode="sideways"), dict(safety_margin=-1.0)])
def test_config_rejects_bad_values(bad):
    with pytest.raises(ValueError):
        AvoidanceConfig(**bad)
