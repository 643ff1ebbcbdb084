"""Whole runs: takeoff, the case0 mission with and without avoidance, statuses, seeds, batches, distances."""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from surrealist_gym import Mission, MissionItem, Obstacle, TestCase
from surrealist_gym.errors import SimulationError
from surrealist_gym.geometry import obstacle_distances
from surrealist_gym.mission import Command
from surrealist_gym.sim import NoiseConfig, RunStatus, SimConfig, simulate, simulate_runs
from surrealist_gym.sim.sensing.noise import run_seed_sequence

LAND_XY = (-16.645876487856597, 6.859186808331832)  # case0.plan's landing point [m from home]
OFF = SimConfig(avoidance=False)
ON = SimConfig(avoidance=True)


def _mission(*items):
    return Mission(items=tuple(items), home=(47.0, 8.0, 400.0))


def test_takeoff_reaches_the_takeoff_altitude():
    test = TestCase(mission=_mission(MissionItem(Command.TAKEOFF, 0.0, 0.0, 5.0)), params={"MPC_TKO_SPEED": 1.5})
    (r,) = simulate(test, runs=1, config=replace(OFF, takeoff_delay_s=1.0))
    assert r.status == RunStatus.SUCCESS and "in the air" in r.message
    assert r.true_xyz[-1, 2] == pytest.approx(5.0, abs=0.8)  # accepted within NAV_MC_ALT_RAD
    climb = np.diff(r.true_xyz[:, 2]) / np.diff(r.true_t)
    assert climb.max() == pytest.approx(1.5, abs=0.2)  # MPC_TKO_SPEED


@pytest.mark.slow
def test_straight_into_the_box_without_avoidance_collides(blocked):
    (r,) = simulate(blocked, runs=1, config=OFF)
    assert r.status == RunStatus.COLLISION
    assert r.min_distance < 0.5
    assert 8.0 < r.duration < 25.0


@pytest.mark.slow
def test_avoidance_detours_and_lands_near_the_landing_point(blocked):
    (r,) = simulate(blocked, runs=1, config=ON)
    assert r.status == RunStatus.SUCCESS, r.message
    assert r.min_distance > 0.5
    end = r.true_xyz[-1]
    assert math.hypot(end[0] - LAND_XY[0], end[1] - LAND_XY[1]) < 3.0
    assert end[2] < 0.2
    # slowed down around the obstacle, as the real flight did (~0.7 m/s)
    speed = np.hypot(r.local_position.vx, r.local_position.vy)
    assert np.median(speed[speed > 0.3]) < 1.5


@pytest.mark.slow
def test_case0_params_come_from_test_and_reference_log(seed1):
    (r,) = simulate(seed1, runs=1, config=replace(ON, timeout_s=5.0))
    assert r.status == RunStatus.TIMEOUT
    assert r.params["MPC_THR_HOVER"] == pytest.approx(0.3)   # from case0.ulg
    assert r.params["NAV_ACC_RAD"] == 0.5                     # the test's params beat the log's 2.0
    assert r.params["COM_OBS_AVOID"] == 1


def test_same_seed_same_trajectory_different_seeds_differ(free):
    cfg = replace(OFF, timeout_s=14.0)
    a = simulate(free, runs=2, seed=7, config=cfg)
    b = simulate(free, runs=2, seed=7, config=cfg)
    c = simulate(free, runs=1, seed=8, config=cfg)
    assert a[0].trajectory == b[0].trajectory and a[1].trajectory == b[1].trajectory
    assert a[0].trajectory != a[1].trajectory
    assert a[0].trajectory != c[0].trajectory
    spread = np.abs(a[0].trajectory.xyz - a[1].trajectory.xyz[:len(a[0].trajectory)]).max()
    assert 0.01 < spread < 2.0  # a realistic spread, not a different flight


def test_without_noise_every_seed_flies_the_same(free):
    cfg = replace(OFF, timeout_s=8.0, noise=NoiseConfig.off())
    a, b = simulate(free, runs=2, seed=1, config=cfg)
    assert a.trajectory == b.trajectory


@pytest.mark.slow
def test_batch_equals_single_runs(blocked):
    """Runs flown together in one world are bit-identical to the same runs flown alone."""
    cfg = replace(ON, timeout_s=20.0)
    batch = simulate(blocked, runs=3, seed=5, config=cfg)
    for r in batch:
        (single,) = simulate_runs(blocked, [r.index], seed=5, config=cfg)
        assert single.trajectory == r.trajectory
        assert single.status == r.status and single.duration == r.duration


@pytest.mark.slow
def test_distances_agree_with_geometry(blocked):
    (r,) = simulate(blocked, runs=1, config=ON)
    d3 = obstacle_distances(r.true_xyz, blocked.obstacles, dims=3)
    d2 = obstacle_distances(r.true_xyz, blocked.obstacles, dims=2)
    assert r.min_distance == pytest.approx(d3.min())
    assert r.min_distance_2d == pytest.approx(d2.min())
    (c,) = r.clearances
    assert c.time == pytest.approx(r.true_t[np.argmin(d3[:, 0])])
    assert 0.0 <= c.time <= r.duration


def test_timeout_and_no_obstacles(free):
    (r,) = simulate(free, runs=1, config=replace(OFF, timeout_s=3.0))
    assert r.status == RunStatus.TIMEOUT
    assert r.duration == pytest.approx(3.0, abs=0.01)
    assert r.min_distance == math.inf and r.clearances == ()


def test_stuck_behind_a_wall():
    wall = Obstacle(1.0, 40.0, 30.0, 8.0, 0.0)
    test = TestCase(mission=_mission(MissionItem(Command.TAKEOFF, 0.0, 0.0, 3.0),
                                     MissionItem(Command.WAYPOINT, 20.0, 0.0, 3.0)),
                    obstacles=(wall,), params={"NAV_ACC_RAD": 1.0})
    (r,) = simulate(test, runs=1, config=replace(ON, takeoff_delay_s=0.5, stuck_window_s=4.0, timeout_s=60.0))
    assert r.status in (RunStatus.STUCK, RunStatus.TIMEOUT)
    assert r.status == RunStatus.STUCK, r.message
    assert r.min_distance > 0.3


def test_trajectory_goes_through_the_pipeline(free):
    (r,) = simulate(free, runs=1, config=replace(OFF, timeout_s=6.0))
    lp = r.local_position
    assert np.all(np.diff(lp.timestamp_us) > 0)
    assert np.median(np.diff(lp.timestamp_us)) == pytest.approx(1e5)  # log_hz = 10
    assert r.trajectory.xyz[0] == pytest.approx([lp.x[:5].mean() - lp.x[0], lp.y[:5].mean() - lp.y[0],
                                                 -(lp.z[:5].mean() - lp.z[0])])
    assert np.diff(r.trajectory.t)[:-1] == pytest.approx(0.5, abs=1e-6)  # the last window may be partial


def test_errors_and_config_checks(free):
    with pytest.raises(SimulationError):
        simulate(TestCase(), runs=1)
    with pytest.raises(TypeError, match="unknown field 'physic_hz'"):
        SimConfig.from_dict({"physic_hz": 300})
    with pytest.raises(ValueError):
        SimConfig(physics_hz=100)
    with pytest.raises(ValueError):
        simulate(free, runs=0)


def test_run_seeds_depend_on_test_seed_and_index(free, seed1):
    state = lambda s: s.generate_state(4).tolist()  # noqa: E731
    assert state(run_seed_sequence(free.key(), 0, 0)) == state(run_seed_sequence(free.key(), 0, 0))
    others = [run_seed_sequence(free.key(), 1, 0), run_seed_sequence(free.key(), 0, 1),
              run_seed_sequence(seed1.key(), 0, 0)]
    assert all(state(o) != state(run_seed_sequence(free.key(), 0, 0)) for o in others)


def test_common_noise_flies_two_tests_under_the_same_noise(free):
    """Common random numbers: run i draws its noise from (seed, i) alone, so a far-away box changes nothing."""
    far = free.with_obstacles([Obstacle(l=1.0, w=1.0, h=1.0, x=200.0, y=200.0)])
    cfg = replace(OFF, timeout_s=10.0)
    common = replace(cfg, common_noise=True)
    (a,), (b,) = simulate(free, runs=1, seed=3, config=common), simulate(far, runs=1, seed=3, config=common)
    assert a.trajectory == b.trajectory
    (c,), (d,) = simulate(free, runs=1, seed=3, config=cfg), simulate(far, runs=1, seed=3, config=cfg)
    assert c.trajectory != d.trajectory  # by default each test draws its own noise
