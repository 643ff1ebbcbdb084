"""The compiled run loop (``sim/compiled/loop.py``, what ``SimConfig(physics="compiled")`` flies) against its
reference, the Python ``_outer`` per outer period with the compiled physics (``runner._fly_compiled_outer``): the
same RunResults bit for bit (statuses, messages, durations, true trajectories, logged estimates, competition
distances), with both planners, without avoidance, without noise, and for successes, collisions, time-outs and stuck
runs."""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from surrealist_gym import Mission, MissionItem, Obstacle, TestCase
from surrealist_gym.mission import Command
from surrealist_gym.sim import NoiseConfig, Physics, RunStatus, SimConfig, runner, simulate
from surrealist_gym.sim.sensing.noise import NoiseSource, run_seed_sequence
from surrealist_gym.sim.uav import decide_uav
from tests.surrealist_gym.sim.vehicle.test_compiled_physics import rilast_case, shipped_scenarios


def _fly_both(test, runs, config, monkeypatch):
    config = dataclasses.replace(config, physics=Physics.COMPILED, tree_reuse_m=0.0)  # the reference builds every cycle
    new = simulate(test, runs=runs, seed=0, config=config)
    calls = []

    def reference(*args):
        calls.append(1)
        runner._fly_compiled_outer(*args)

    with monkeypatch.context() as m:
        m.setattr(runner, "_fly_compiled", reference)
        old = simulate(test, runs=runs, seed=0, config=config)
    assert calls == [1]
    return old, new


def _assert_same(old, new, name):
    assert len(old) == len(new)
    for a, b in zip(old, new):
        assert (a.status, a.message, a.duration, a.index) == (b.status, b.message, b.duration, b.index), name
        assert np.array_equal(a.true_t, b.true_t) and np.array_equal(a.true_xyz, b.true_xyz), name
        for f in ("timestamp_us", "x", "y", "z", "vx", "vy", "vz", "heading"):
            assert np.array_equal(getattr(a.local_position, f), getattr(b.local_position, f)), (name, f)
        assert (a.competition_distance == b.competition_distance
                or math.isnan(a.competition_distance) and math.isnan(b.competition_distance)), name
        assert (a.min_distance, a.min_distance_2d, a.clearances) == (b.min_distance, b.min_distance_2d,
                                                                     b.clearances), name


def test_noise_blocks_are_the_series_of_at():
    """NoiseSource.block gives the same values, block after block, as NoiseSource.at (wind plugin included)."""
    from surrealist_gym import Wind

    wind = Wind(velocity_mean=6.0, velocity_variance=1.0, direction=(0.0, 1.0, 0.0), gust_start=3.0,
                gust_duration=4.0, gust_velocity_mean=3.0)
    for config in (NoiseConfig(), NoiseConfig(planner_jitter_s=0.05, start_jitter_s=0.6)):
        a = NoiseSource(run_seed_sequence("k", 3, 1), config, wind, 0.02)
        b = NoiseSource(run_seed_sequence("k", 3, 1), config, wind, 0.02)
        assert a.start_offset == b.start_offset
        rows = np.concatenate([b.block() for _ in range(3)])
        for k in range(3 * NoiseSource.BLOCK):
            pe, ve, yaw_err, w = a.at(k)
            assert tuple(rows[k]) == (*pe, *ve, yaw_err, *w, float(a.plans(k)))
    # the depth sensor's range noise: consecutive draws concatenate, so the loop draws several scans at once
    g1, g2 = (np.random.default_rng(7) for _ in range(2))
    assert np.array_equal(np.concatenate([g1.standard_normal(384) * 0.02 for _ in range(5)]),
                          g2.standard_normal(384 * 5) * 0.02)


@pytest.mark.filterwarnings("ignore:.*is not supported")
def test_compiled_loop_equals_the_python_outer_loop(monkeypatch):
    """Two runs of every scenario of the physics agreement test (PX4 Vision with the simple planner; SITL Iris
    with PX4-Avoidance: 1-3 boxes, cylinders, wind): the same results bit for bit."""
    total = 0
    for name, test in shipped_scenarios().items():
        old, new = _fly_both(test, 2, decide_uav(test).config, monkeypatch)
        _assert_same(old, new, name)
        total += len(new)
    assert total == 14


@pytest.mark.filterwarnings("ignore:.*is not supported")
def test_compiled_loop_equals_the_python_outer_loop_with_the_sitl_timing(monkeypatch):
    """The SITL timing (planner cycles from a per-run phase, each planning late; the mission start moved): both loops
    fly the same runs bit for bit, on every scenario with avoidance."""
    from surrealist_gym.sim.profiles import SITL_TIMING

    total = 0
    for name, test in shipped_scenarios().items():
        config = decide_uav(test).config
        config = dataclasses.replace(config, noise=dataclasses.replace(config.noise, **SITL_TIMING))
        old, new = _fly_both(test, 2, config, monkeypatch)
        _assert_same(old, new, name)
        total += len(new)
    assert total == 14


def test_compiled_loop_collision_timeout_and_stuck(monkeypatch):
    """Without avoidance into a box (noisy, and noiseless), a time limit in the middle of a PX4-Avoidance flight,
    and the stuck check: the same results bit for bit."""
    mission = Mission(items=(MissionItem(Command.TAKEOFF, 0.0, 0.0, 5.0),
                             MissionItem(Command.WAYPOINT, 20.0, 0.0, 5.0)), home=(47.0, 8.0, 400.0))
    box = TestCase(mission=mission, obstacles=(Obstacle(2.0, 6.0, 10.0, 10.0, 0.0, 0.0, 20.0),))
    for noise in (NoiseConfig(), NoiseConfig.off()):
        old, new = _fly_both(box, 2, SimConfig(avoidance=False, noise=noise, takeoff_delay_s=1.0), monkeypatch)
        assert [r.status for r in new] == [RunStatus.COLLISION] * 2
        _assert_same(old, new, "collision")
    test = rilast_case("random_run3_194")
    cfg = dataclasses.replace(decide_uav(test).config, timeout_s=21.37)
    old, new = _fly_both(test, 2, cfg, monkeypatch)
    assert [r.status for r in new] == [RunStatus.TIMEOUT] * 2
    _assert_same(old, new, "timeout")
    cfg = dataclasses.replace(decide_uav(test).config, stuck_window_s=2.0, stuck_distance_m=3.0)
    old, new = _fly_both(test, 1, cfg, monkeypatch)
    assert new[0].status == RunStatus.STUCK
    _assert_same(old, new, "stuck")


@pytest.mark.filterwarnings("ignore:.*is not supported")
def test_compiled_loop_without_noise(monkeypatch):
    """Both planners with every noise off (the scan without range noise) and with the depth sensor's own noise off:
    the same results bit for bit."""
    scenarios = shipped_scenarios()
    for name in ("rq1-seed1", "rilast 2 boxes"):
        test = scenarios[name]
        base = decide_uav(test).config
        for noise in (NoiseConfig.off(), dataclasses.replace(base.noise, sensor=False)):
            old, new = _fly_both(test, 1, dataclasses.replace(base, noise=noise), monkeypatch)
            _assert_same(old, new, name)
